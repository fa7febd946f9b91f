// The page of `blockstack serve`: plain JavaScript, no build step. It draws what the server
// sends (a "view") and sends one message per key press or click; the server decides
// everything, so the page holds no rules of the world. It also leads a study's participant
// (consent, instructions, the end) and shows the researcher's page and replays.
"use strict";

const PACES = [0.5, 1, 2, 4, 6, 8, 12, 15];
const CELL = 56;
// The time a block takes to fall or travel on the page, in milliseconds.
const FALL_MS = 320;
const $ = (id) => document.getElementById(id);

let socket = null;
let view = null;
let nextId = 1;
let running = false;
let waiting = false;
let timer = null;
// When the page showed the current episode's first view (performance.now(), monotonic):
// every action carries its time since then, so the recording has reaction times.
let shownAt = performance.now();
let shownKey = null;
// Side view: the block clicked for a block move, waiting for its destination.
let selected = null;
// A block on its way (a fall or a move), drawn between cells: {block, path, start}.
let moving = null;
let redirected = false;

function show(id) {
  for (const s of ["join", "consent", "declined", "instructions", "session", "end", "withdrawn", "results", "replay", "curve"]) {
    $(s).hidden = s !== id;
  }
}

function send(message) {
  if (!socket || socket.readyState !== WebSocket.OPEN) return;
  message.id = nextId++;
  if (["act", "accept", "move"].includes(message.type)) message.t_ms = Math.round(performance.now() - shownAt);
  waiting = true;
  socket.send(JSON.stringify(message));
}

function act(action) { selected = null; send({ type: "act", action }); }

// Close codes after which the page does not come back by itself (serve::server::close):
// an unknown or let-go session (1008), the session opened in another window (4001).
const FINAL_CLOSES = [1008, 4001];

function connect(token) {
  const scheme = location.protocol === "https:" ? "wss" : "ws";
  socket = new WebSocket(`${scheme}://${location.host}/ws/${token}`);
  socket.onmessage = (event) => {
    const m = JSON.parse(event.data);
    waiting = false;
    if (m.type === "error") {
      $("error").textContent = m.message;
      // An agent running into an error stops, so that the person can read it.
      if (running && view && view.mode !== "watch") setRunning(false);
      return;
    }
    $("error").textContent = "";
    const before = view;
    view = m;
    const key = `${m.mode}/${m.episode}`;
    if (key !== shownKey) {
      shownKey = key;
      shownAt = performance.now();
      selected = null;
    } else if (before && m.view === "side") {
      startMove(before, m);
    }
    draw();
    if (m.done && m.completion) finish(m.completion);
  };
  socket.onclose = (event) => {
    setRunning(false);
    waiting = false;
    if (FINAL_CLOSES.includes(event.code) || event.code === 1009) {
      if (!$("error").textContent) $("error").textContent = event.reason || "The connection to the server is closed.";
      return;
    }
    if (!$("end").hidden || !$("withdrawn").hidden) return;
    // A connection lost or let go while idle: the session is still there; come back to it.
    $("error").textContent = "Reconnecting...";
    setTimeout(() => connect(token), 1000);
  };
}

// The end of a study: the completion code, then the platform's completion link.
function finish(completion) {
  setRunning(false);
  if (!$("end").hidden) return;
  setTimeout(() => {
    show("end");
    $("codeline").hidden = !completion.code;
    $("code").textContent = completion.code || "";
    if (completion.url && !redirected) {
      redirected = true;
      $("redirect").textContent = "Taking you back to the study's site in a moment...";
      setTimeout(() => { location.href = completion.url; }, 2500);
    }
  }, 1200);
}

// ---- Drawing -------------------------------------------------------------------------

// The path a block takes between two views of the side view: straight down when it was
// dropped, up over the towers, across and down when it was moved by a block move.
function startMove(before, after) {
  const [, h] = after.grid;
  for (let b = 0; b < after.blocks.length; b++) {
    const [x0, y0] = before.blocks[b];
    const [x1, y1] = after.blocks[b];
    if (x0 === x1 && y0 === y1) continue;
    let path;
    if (before.held === b && after.held !== b && x0 === x1) path = [[x0, y0], [x1, y1]];
    else if (before.held !== b && after.held !== b) path = [[x0, y0], [x0, h - 1], [x1, h - 1], [x1, y1]];
    else continue;
    moving = { block: b, path, start: performance.now() };
    requestAnimationFrame(animate);
    return;
  }
}

function animate() {
  if (!moving) return;
  draw();
  if (performance.now() - moving.start < FALL_MS) requestAnimationFrame(animate);
  else { moving = null; draw(); }
}

// Where the moving block is drawn now (in cells, y up), along its path.
function movingAt() {
  const t = Math.min(1, (performance.now() - moving.start) / FALL_MS);
  const legs = moving.path.length - 1;
  const leg = Math.min(legs - 1, Math.floor(t * legs));
  const f = t * legs - leg;
  const [a, b] = [moving.path[leg], moving.path[leg + 1]];
  return [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f];
}

function drawBlock(ctx, scene, i, px, py, size, held, picked) {
  ctx.fillStyle = scene.colours[i];
  ctx.fillRect(px + 2, py + 2, size - 4, size - 4);
  if (held || picked) {
    ctx.lineWidth = 4;
    ctx.strokeStyle = "#111";
    if (picked) ctx.setLineDash([6, 4]);
    ctx.strokeRect(px + 4, py + 4, size - 8, size - 8);
    ctx.setLineDash([]);
  }
  ctx.fillStyle = "white";
  ctx.font = `bold ${Math.round(size * 0.45)}px sans-serif`;
  ctx.textAlign = "center";
  ctx.textBaseline = "middle";
  ctx.fillText(scene.labels[i], px + size / 2, py + size / 2 + 1);
}

// A world (the session's view, or a replayed state) on `canvas`: the grid, the blocks,
// in the side view the table under row 0.
function drawWorld(canvas, scene, state) {
  const [w, h] = scene.grid;
  canvas.width = w * CELL;
  canvas.height = h * CELL + (scene.view === "side" ? 8 : 0);
  const ctx = canvas.getContext("2d");
  ctx.fillStyle = "white";
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  ctx.strokeStyle = "#ddd";
  ctx.lineWidth = 1;
  for (let x = 0; x <= w; x++) { ctx.beginPath(); ctx.moveTo(x * CELL, 0); ctx.lineTo(x * CELL, h * CELL); ctx.stroke(); }
  for (let y = 0; y <= h; y++) { ctx.beginPath(); ctx.moveTo(0, y * CELL); ctx.lineTo(w * CELL, y * CELL); ctx.stroke(); }
  if (scene.view === "side") {
    ctx.fillStyle = "#8b5a2b";
    ctx.fillRect(0, h * CELL, w * CELL, 8);
  }
  state.blocks.forEach(([x, y], i) => {
    if (moving && moving.block === i && state === view) [x, y] = movingAt();
    drawBlock(ctx, scene, i, x * CELL, (h - 1 - y) * CELL, CELL, state.held === i, selected === i && state === view);
  });
}

// The goal: its towers side by side, each bottom block at the bottom (a goal of one tower
// comes as its list of blocks, a goal of towers as {towers, blocks}); a table in the side
// view.
function drawGoal(canvas, scene) {
  const towers = Array.isArray(scene.goal) ? [scene.goal] : scene.goal.towers;
  const gs = 40;
  const tallest = Math.max(...towers.map((t) => t.length));
  canvas.height = gs * tallest + 12;
  canvas.width = (gs + 6) * towers.length + 8;
  const gc = canvas.getContext("2d");
  gc.clearRect(0, 0, canvas.width, canvas.height);
  towers.forEach((tower, i) => {
    tower.forEach((b, place) => drawBlock(gc, scene, b, 4 + i * (gs + 6), canvas.height - 8 - (place + 1) * gs, gs, false, false));
  });
  if (scene.view === "side") {
    gc.fillStyle = "#8b5a2b";
    gc.fillRect(0, canvas.height - 8, canvas.width, 4);
  }
}

function draw() {
  drawWorld($("world"), view, view);
  drawGoal($("goal"), view);

  $("condition").textContent = `condition ${view.condition}`;
  const nav = $("modes");
  nav.replaceChildren(...view.modes.map((m) => {
    const b = document.createElement("button");
    b.textContent = m;
    b.dataset.mode = m;
    b.className = m === view.mode ? "active" : "";
    b.onclick = () => { setRunning(false); send({ type: "mode", mode: m }); };
    return b;
  }));

  const p = view.progress;
  const lines = [`episode ${view.episode + 1}, ${view.steps} steps`];
  if (view.over) lines.push(`ended: ${view.outcome}` + (view.shortest !== null ? ` (shortest plan: ${view.shortest})` : ""));
  if (view.proposal) lines.push(`the agent proposes: ${view.proposal}`);
  if (view.greedy) lines.push(`the agent's choice: ${view.greedy}`);
  const total = p.episodes_total ? ` of ${p.episodes_total}` : "";
  lines.push(`episodes done: ${p.episodes_done}${total}; your steps: ${p.corrections}`);
  if (view.recording) lines.push(`recorded lines: ${p.recorded_lines}`);
  if (view.done) lines.push("All episodes done: thank you!");
  $("status").textContent = lines.join("\n");

  const best = view.greedy || view.proposal;
  $("qvalues").hidden = view.q.length === 0;
  $("qvalues").querySelector("tbody").replaceChildren(...view.q.map(({ action, q }) => {
    const tr = document.createElement("tr");
    if (action === best) tr.className = "greedy";
    for (const text of [action, q.toFixed(3)]) {
      const td = document.createElement("td");
      td.textContent = text;
      tr.appendChild(td);
    }
    return tr;
  }));
  $("message").textContent = view.message;

  const watch = view.mode === "watch";
  $("moves").hidden = watch;
  $("accept").hidden = view.mode !== "correct";
  $("run").hidden = view.mode === "play";
  $("pacebox").hidden = view.mode === "play";
  $("withdraw").hidden = !view.withdrawal;
  $("help").textContent = view.view === "side"
    ? "Click a clear block, then the column to put it on (a block move); or press its label to pick it, move it with the arrows and drop it with d: it falls."
    : "Click a block or press its label to pick it; arrows (or a click beside the held block) move it; d drops.";
}

function setRunning(on) {
  running = on;
  $("run").textContent = on ? "pause (space)" : "run (space)";
  clearInterval(timer);
  timer = null;
  if (on) {
    const pace = PACES[Number($("pace").value)];
    timer = setInterval(() => {
      if (waiting || !view) return;
      if (view.mode === "watch") send({ type: "step" });
      else if (view.mode === "correct") send(view.over ? { type: "next" } : { type: "accept" });
    }, 1000 / pace);
  }
}

function onKey(event) {
  if (!view || event.target.tagName === "INPUT") return;
  const key = event.key;
  const moves = { ArrowUp: "up", ArrowDown: "down", ArrowLeft: "left", ArrowRight: "right" };
  if (moves[key] && view.mode !== "watch") act(moves[key]);
  else if (key === "d" && view.mode !== "watch") act("drop");
  else if (/^[0-9A-F]$/.test(key) && view.mode !== "watch") act(`pick ${parseInt(key, 16)}`);
  else if (key === "Enter" && view.mode === "correct") send({ type: "accept" });
  else if (key === "n") send({ type: "next" });
  else if (key === " " && view.mode !== "play") setRunning(!running);
  else if (key === "+" || key === "=") { $("pace").value = Math.min(7, Number($("pace").value) + 1); pace(); }
  else if (key === "-") { $("pace").value = Math.max(0, Number($("pace").value) - 1); pace(); }
  else if (key === "Escape") { selected = null; draw(); }
  else return;
  event.preventDefault();
}

function pace() {
  $("pacetext").textContent = `${PACES[Number($("pace").value)]} steps/s`;
  if (running) setRunning(true);
}

function cellAt(x, y) {
  const [w, h] = view.grid;
  return [Math.floor(x / CELL), h - 1 - Math.floor(y / CELL)].filter(() => x >= 0 && y >= 0 && x < w * CELL && y < h * CELL);
}

function blockAt(cx, cy) {
  return view.blocks.findIndex(([x, y]) => x === cx && y === cy);
}

function onClick(event) {
  if (!view || view.mode === "watch") return;
  const rect = $("world").getBoundingClientRect();
  const cell = cellAt(event.clientX - rect.left, event.clientY - rect.top);
  if (cell.length < 2) return;
  const [cx, cy] = cell;
  const b = blockAt(cx, cy);
  if (view.view === "side" && view.held === null) {
    // A block move: a clear block, then the column it goes to.
    if (selected === null) {
      if (b >= 0) { selected = b; draw(); }
      return;
    }
    const from = view.blocks[selected][0];
    const block = selected;
    selected = null;
    if (cx === from) { draw(); return; }
    send({ type: "move", block, to: cx });
    return;
  }
  if (b >= 0) return act(`pick ${b}`);
  // A click beside the held block moves it there.
  if (view.held === null) return;
  const [hx, hy] = view.blocks[view.held];
  const dir = { "0,1": "up", "0,-1": "down", "-1,0": "left", "1,0": "right" }[`${cx - hx},${cy - hy}`];
  if (dir) act(dir);
  else $("error").textContent = "Click a block to pick it, or a cell beside the held block to move it there.";
}

async function withdraw(token) {
  if (!confirm("Withdraw from the study? What you did will not be used.")) return;
  const r = await fetch(`/api/withdraw/${token}`, { method: "POST" });
  if (!r.ok) { $("error").textContent = await r.text(); return; }
  const { withdrawal, completion } = await r.json();
  setRunning(false);
  if (socket) { socket.onclose = null; socket.close(); }
  show("withdrawn");
  $("withdrawntext").textContent = withdrawal === "delete"
    ? "Your recording was deleted. Thank you for your time; you may close this page."
    : "Your recording is marked withdrawn and left out of every analysis. Thank you for your time; you may close this page.";
  // A study may give the completion code to those who withdraw too.
  if (completion && completion.code) {
    $("withdrawncodeline").hidden = false;
    $("withdrawncode").textContent = completion.code;
  }
}

// ---- A study's first pages -----------------------------------------------------------

// The platform's ids from this page's URL (only those the study reads).
function urlIds(study) {
  const params = new URLSearchParams(location.search);
  const ids = {};
  for (const key of study.participant_ids) if (params.get(key)) ids[key] = params.get(key);
  return ids;
}

function hiddenField(form, name, value) {
  const input = document.createElement("input");
  input.type = "hidden";
  input.name = name;
  input.value = value;
  form.appendChild(input);
}

async function arrive() {
  const study = await (await fetch("/api/study")).json();
  const ids = urlIds(study);
  for (const form of [$("joinform"), $("studyform")]) {
    for (const [k, v] of Object.entries(ids)) hiddenField(form, k, v);
  }
  if (Object.keys(ids).length > 0) {
    // A participant who comes back in the same browser goes on with their session: the
    // server knows it by the token this browser keeps (a cookie), never by the ids.
    const r = await fetch("/api/resume", { method: "POST", body: new URLSearchParams(ids) });
    const back = r.ok ? await r.json() : {};
    if (back.token) { location.href = `/s/${back.token}`; return; }
    if (back.withdrawn) {
      show("withdrawn");
      $("withdrawntext").textContent = "You withdrew from this study: nothing more is recorded for you.";
      return;
    }
    $("namebox").hidden = true;
  }
  const instructions = () => {
    if (study.instructions) {
      $("instructionstext").innerHTML = study.instructions;
      $("consentfield").value = "agree";
      show("instructions");
    } else if (study.consent) {
      $("consentfield").value = "agree";
      $("studyform").submit();
    } else {
      show("join");
    }
  };
  if (study.consent) {
    // Rendered by the server from the study's Markdown, with nothing in it that runs.
    $("consenttext").innerHTML = study.consent;
    show("consent");
    $("agree").onclick = instructions;
    $("decline").onclick = () => show("declined");
  } else {
    instructions();
  }
}

// ---- The researcher's page and the replay --------------------------------------------

function cells(tbody, rows) {
  tbody.replaceChildren(...rows.map((row) => {
    const tr = document.createElement("tr");
    for (const item of row) {
      const td = document.createElement("td");
      if (item instanceof Node) td.appendChild(item); else td.textContent = String(item);
      tr.appendChild(td);
    }
    return tr;
  }));
}

const share = (v) => (v === null ? "-" : `${(100 * v).toFixed(0)}%`);
const ms = (v) => (v === null || v === undefined ? "-" : `${(v / 1000).toFixed(2)} s`);

async function results(token) {
  show("results");
  $("csv").href = `/api/results/${token}/episodes.csv`;
  const refresh = async () => {
    const r = await fetch(`/api/results/${token}`);
    if (!r.ok) { $("study").textContent = await r.text(); return; }
    const data = await r.json();
    const cap = data.max_participants ? `, ${data.admitted} of at most ${data.max_participants} participants` : "";
    $("study").textContent = `${data.study}: conditions ${data.conditions.join(", ")}${cap}`;
    const left = data.table.withdrawn;
    $("leftout").textContent = left
      ? `${left} withdrawn participant${left === 1 ? "" : "s"} left out of these tables, the CSV and the replays.`
      : "";
    cells($("conditions").querySelector("tbody"), data.table.conditions.map((c) => [
      c.condition, c.view, c.participants, c.episodes, share(c.success),
      c.steps_to_optimum === null ? "-" : `${c.steps_to_optimum.toFixed(2)}x`, c.corrections, ms(c.median_rt_ms),
    ]));
    cells($("sessions").querySelector("tbody"), data.sessions.map((s) => {
      const p = s.progress;
      const state = s.withdrawn ? " (withdrew)" : s.done ? " (done)" : "";
      const episodes = `${p.episodes_done}${p.episodes_total ? " / " + p.episodes_total : ""}${state}`;
      return [s.number, s.name || "", s.id || "", s.condition, s.mode, s.connected ? "yes" : "no", episodes, p.steps, p.corrections, p.recorded_lines, s.recording || ""];
    }));
    cells($("episodes").querySelector("tbody"), data.table.episodes.map((e) => {
      const a = document.createElement("a");
      a.href = `/replay/${token}/${encodeURIComponent(e.recording)}/${e.episode}`;
      a.textContent = "replay";
      a.className = "replaylink";
      return [e.participant, e.participant_id || e.code || "", e.condition, e.view, e.goal, e.episode, e.steps,
        e.optimum === null ? "-" : e.optimum, e.ended ? (e.success ? "yes" : "no") : "unfinished", e.corrections,
        ms(e.duration_ms), ms(e.median_rt_ms), a];
    }));
  };
  $("resumeform").onsubmit = async (event) => {
    event.preventDefault();
    const r = await fetch(`/api/results/${token}/resume`, {
      method: "POST",
      body: new URLSearchParams({ participant: $("resumenumber").value }),
    });
    $("resumelink").textContent = r.ok ? (await r.json()).link : await r.text();
  };
  await refresh();
  setInterval(refresh, 2000);
}

async function replay(token, file, episode) {
  show("replay");
  const r = await fetch(`/api/replay/${token}/${file}/${episode}`);
  if (!r.ok) { $("replaytitle").textContent = await r.text(); return; }
  const rec = await r.json();
  let k = 0;
  let playing = null;
  $("replaytitle").textContent = `participant ${rec.row.participant} (${rec.row.condition}, ${rec.view} view), episode ${rec.row.episode}: ${rec.row.steps} steps, shortest ${rec.row.optimum ?? "-"}`;
  const at = () => (k === 0 ? rec.start : rec.steps[k - 1].state);
  const render = () => {
    drawWorld($("replayworld"), rec, at());
    drawGoal($("replaygoal"), rec);
    const s = rec.steps[k - 1];
    $("replaystatus").textContent = k === 0
      ? `start (step 0 of ${rec.steps.length})`
      : `step ${k} of ${rec.steps.length}: ${s.action} (${s.person ? "the person" : "the agent"})${s.t_ms === null ? "" : ` at ${ms(s.t_ms)}`}`;
  };
  const stop = () => { clearInterval(playing); playing = null; $("replayplay").textContent = "play"; };
  $("replayfirst").onclick = () => { stop(); k = 0; render(); };
  $("replayprev").onclick = () => { stop(); k = Math.max(0, k - 1); render(); };
  $("replaynext").onclick = () => { stop(); k = Math.min(rec.steps.length, k + 1); render(); };
  $("replayplay").onclick = () => {
    if (playing) return stop();
    $("replayplay").textContent = "pause";
    playing = setInterval(() => {
      if (k >= rec.steps.length) return stop();
      k += 1;
      render();
    }, 1000 / PACES[Number($("replaypace").value)]);
  };
  render();
}

// A training run's learning curve: the share of recent games that reached the goal (blue,
// left axis) and their mean steps (orange, right axis) against games played.
async function curve() {
  show("curve");
  const draw = (data) => {
    $("curvetitle").textContent = data.title;
    const c = $("chart");
    const ctx = c.getContext("2d");
    const [w, h, pad] = [c.width, c.height, 40];
    ctx.clearRect(0, 0, w, h);
    ctx.strokeStyle = "#999";
    ctx.strokeRect(pad, 10, w - 2 * pad, h - pad - 10);
    const pts = data.points;
    // The games played so far fill the width: the curve grows into view as the run goes on.
    const xmax = Math.max(1, ...pts.map((p) => p.games));
    const smax = Math.max(1, ...pts.map((p) => p.mean_steps || 0));
    const x = (g) => pad + (w - 2 * pad) * g / xmax;
    const y = (v) => h - pad - (h - pad - 10) * v;
    const line = (colour, value) => {
      ctx.strokeStyle = colour;
      ctx.lineWidth = 2;
      ctx.beginPath();
      let started = false;
      for (const p of pts) {
        const v = value(p);
        if (v === null) continue;
        if (started) ctx.lineTo(x(p.games), y(v)); else ctx.moveTo(x(p.games), y(v));
        started = true;
      }
      ctx.stroke();
    };
    line("#266ed2", (p) => p.success_rate);
    line("#f0961e", (p) => (p.mean_steps === null ? null : p.mean_steps / smax));
    ctx.fillStyle = "#222";
    ctx.font = "12px sans-serif";
    ctx.fillText("0", pad - 12, h - pad);
    ctx.fillText("100%", 2, 20);
    ctx.textAlign = "right";
    ctx.fillText(`${smax.toFixed(0)} steps`, w - pad - 4, 24);
    ctx.textAlign = "left";
    ctx.fillText(`${xmax} games`, w - pad - 50, h - pad + 15);
    const last = pts[pts.length - 1];
    $("curvenote").textContent = last
      ? `${last.games} of ${data.target} games; recent games reaching the goal ${(100 * last.success_rate).toFixed(0)}% (blue), mean steps ${last.mean_steps === null ? "-" : last.mean_steps.toFixed(1)} (orange)`
      : "Waiting for the first games...";
  };
  const refresh = async () => {
    try {
      const r = await fetch("/api/curve");
      if (r.ok) draw(await r.json());
    } catch (e) {
      $("curvenote").textContent = "The training run has ended (the server is gone).";
    }
  };
  await refresh();
  setInterval(refresh, 1000);
}

function main() {
  const path = location.pathname.split("/").filter(Boolean);
  if (path[0] === "s" && path[1]) {
    show("session");
    for (const b of document.querySelectorAll("[data-act]")) b.onclick = () => act(b.dataset.act);
    $("accept").onclick = () => send({ type: "accept" });
    $("next").onclick = () => send({ type: "next" });
    $("run").onclick = () => setRunning(!running);
    $("withdraw").onclick = () => withdraw(path[1]);
    $("pace").oninput = pace;
    $("world").onclick = onClick;
    document.addEventListener("keydown", onKey);
    pace();
    connect(path[1]);
    $("world").focus();
  } else if (path[0] === "results" && path[1]) {
    results(path[1]);
  } else if (path[0] === "replay" && path[3] !== undefined) {
    replay(path[1], path[2], path[3]);
  } else if (path[0] === "curve") {
    curve();
  } else {
    arrive();
  }
}

main();
