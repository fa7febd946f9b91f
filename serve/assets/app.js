// The page of `blockstack serve`: plain JavaScript, no build step. It draws what the server
// sends (a "view") and sends one message per key press or click; the server decides
// everything, so the page holds no rules of the world.
"use strict";

const PACES = [0.5, 1, 2, 4, 6, 8, 12, 15];
const CELL = 56;
const $ = (id) => document.getElementById(id);

let socket = null;
let view = null;
let nextId = 1;
let running = false;
let waiting = false;
let timer = null;

function show(id) {
  for (const s of ["join", "session", "results", "curve"]) $(s).hidden = s !== id;
}

function send(message) {
  if (!socket || socket.readyState !== WebSocket.OPEN) return;
  message.id = nextId++;
  waiting = true;
  socket.send(JSON.stringify(message));
}

function act(action) { send({ type: "act", action }); }

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
    view = m;
    draw();
  };
  socket.onclose = (event) => {
    setRunning(false);
    waiting = false;
    if (FINAL_CLOSES.includes(event.code) || event.code === 1009) {
      if (!$("error").textContent) $("error").textContent = event.reason || "The connection to the server is closed.";
      return;
    }
    // A connection lost or let go while idle: the session is still there; come back to it.
    $("error").textContent = "Reconnecting...";
    setTimeout(() => connect(token), 1000);
  };
}

function cellAt(x, y) {
  const [w, h] = view.grid;
  return [Math.floor(x / CELL), h - 1 - Math.floor(y / CELL)].filter(() => x >= 0 && y >= 0 && x < w * CELL && y < h * CELL);
}

function blockAt(cx, cy) {
  return view.blocks.findIndex(([x, y]) => x === cx && y === cy);
}

function drawBlock(ctx, i, px, py, size, held) {
  ctx.fillStyle = view.colours[i];
  ctx.fillRect(px + 2, py + 2, size - 4, size - 4);
  if (held) {
    ctx.lineWidth = 4;
    ctx.strokeStyle = "#111";
    ctx.strokeRect(px + 4, py + 4, size - 8, size - 8);
  }
  ctx.fillStyle = "white";
  ctx.font = `bold ${Math.round(size * 0.45)}px sans-serif`;
  ctx.textAlign = "center";
  ctx.textBaseline = "middle";
  ctx.fillText(view.labels[i], px + size / 2, py + size / 2 + 1);
}

function draw() {
  const [w, h] = view.grid;
  const canvas = $("world");
  canvas.width = w * CELL;
  canvas.height = h * CELL;
  const ctx = canvas.getContext("2d");
  ctx.fillStyle = "white";
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  ctx.strokeStyle = "#ddd";
  ctx.lineWidth = 1;
  for (let x = 0; x <= w; x++) { ctx.beginPath(); ctx.moveTo(x * CELL, 0); ctx.lineTo(x * CELL, h * CELL); ctx.stroke(); }
  for (let y = 0; y <= h; y++) { ctx.beginPath(); ctx.moveTo(0, y * CELL); ctx.lineTo(w * CELL, y * CELL); ctx.stroke(); }
  view.blocks.forEach(([x, y], i) => drawBlock(ctx, i, x * CELL, (h - 1 - y) * CELL, CELL, view.held === i));

  if (view.view === "side") {
    // The table the towers stand on, under row 0.
    ctx.fillStyle = "#8b5a2b";
    ctx.fillRect(0, h * CELL - 4, w * CELL, 4);
  }

  // The goal: its towers side by side, each bottom block at the bottom (a goal of one
  // tower comes as its list of blocks, a goal of towers as {towers, blocks}).
  const towers = Array.isArray(view.goal) ? [view.goal] : view.goal.towers;
  const g = $("goal");
  const gs = 40;
  const tallest = Math.max(...towers.map((t) => t.length));
  g.height = gs * tallest + 12;
  g.width = (gs + 6) * towers.length + 8;
  const gc = g.getContext("2d");
  gc.clearRect(0, 0, g.width, g.height);
  towers.forEach((tower, i) => {
    tower.forEach((b, place) => drawBlock(gc, b, 4 + i * (gs + 6), g.height - 8 - (place + 1) * gs, gs, false));
  });
  if (view.view === "side") {
    gc.fillStyle = "#8b5a2b";
    gc.fillRect(0, g.height - 8, g.width, 4);
  }

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
  else return;
  event.preventDefault();
}

function pace() {
  $("pacetext").textContent = `${PACES[Number($("pace").value)]} steps/s`;
  if (running) setRunning(true);
}

function onClick(event) {
  if (!view || view.mode === "watch") return;
  const rect = $("world").getBoundingClientRect();
  const cell = cellAt(event.clientX - rect.left, event.clientY - rect.top);
  if (cell.length < 2) return;
  const [cx, cy] = cell;
  const b = blockAt(cx, cy);
  if (b >= 0) return act(`pick ${b}`);
  // A click beside the held block moves it there.
  if (view.held === null) return;
  const [hx, hy] = view.blocks[view.held];
  const dir = { "0,1": "up", "0,-1": "down", "-1,0": "left", "1,0": "right" }[`${cx - hx},${cy - hy}`];
  if (dir) act(dir);
  else $("error").textContent = "Click a block to pick it, or a cell beside the held block to move it there.";
}

async function results(token) {
  show("results");
  const refresh = async () => {
    const r = await fetch(`/api/results/${token}`);
    if (!r.ok) { $("study").textContent = await r.text(); return; }
    const data = await r.json();
    $("study").textContent = `${data.study}: ${data.sessions.length} of at most ${data.max_sessions} sessions; conditions ${data.conditions.join(", ")}`;
    $("sessions").querySelector("tbody").replaceChildren(...data.sessions.map((s) => {
      const tr = document.createElement("tr");
      const p = s.progress;
      const episodes = `${p.episodes_done}${p.episodes_total ? " / " + p.episodes_total : ""}${s.done ? " (done)" : ""}`;
      for (const text of [s.number, s.name || "", s.condition, s.mode, s.connected ? "yes" : "no", episodes, p.steps, p.corrections, p.recorded_lines, s.recording || ""]) {
        const td = document.createElement("td");
        td.textContent = String(text);
        tr.appendChild(td);
      }
      return tr;
    }));
  };
  await refresh();
  setInterval(refresh, 2000);
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
    $("pace").oninput = pace;
    $("world").onclick = onClick;
    document.addEventListener("keydown", onKey);
    pace();
    connect(path[1]);
    $("world").focus();
  } else if (path[0] === "results" && path[1]) {
    results(path[1]);
  } else if (path[0] === "curve") {
    curve();
  } else {
    show("join");
  }
}

main();
