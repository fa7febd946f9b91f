//! A problem file: its blocks, its facts as written, and the towers they mean.

use std::collections::HashMap;
use std::fmt;
use std::path::Path;

use crate::error::Result;
use crate::towers::{TowerGoal, Towers};

use super::domain::Domain;
use super::error::PddlError;
use super::sexpr::{self, Node, Source};
use super::vocabulary::{ActionNames, Fact, Predicate};

/// The largest problem file read: 64 MiB, about half a million blocks in the competition's
/// layout (a 488-block task is 12 KiB). A larger file is refused before a byte is read.
pub const MAX_PROBLEM_BYTES: u64 = 64 << 20;

/// A Blocks World problem of the 4-operator domain (`pickup`, `putdown`, `stack`,
/// `unstack`), as the planning competitions write it: the blocks, the facts of the initial
/// state and of the goal as the file states them, and the towers they mean (see the module
/// docs for what is read and what is refused).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Problem {
    name: String,
    domain: String,
    blocks: Vec<String>,
    init: Vec<Fact>,
    goal_facts: Vec<Fact>,
    start: Towers,
    goal: TowerGoal,
    actions: ActionNames,
}

/// Names of the predicates read, for messages.
const PREDICATES: &str = "on, on-table, clear, arm-empty and holding (ontable and handempty, the 2000 competition's names, are read as on-table and arm-empty)";

/// The text of the file at `path`, at most `bound` bytes (refused before a byte is read),
/// `what` it is for messages; an error for a file that is not UTF-8.
pub(crate) fn read_text(path: &Path, bound: u64, what: &'static str) -> Result<String> {
    use std::io::Read;
    let shown = path.display().to_string();
    let mut bytes = Vec::new();
    files::open_bounded(path, bound, what)
        .map_err(PddlError::from)?
        .read_to_end(&mut bytes)
        .map_err(|e| PddlError::from(files::FilesError::read(&shown, files::ReadProblem::Io(e.to_string()))))?;
    String::from_utf8(bytes).map_err(|e| {
        PddlError::from(files::FilesError::read(
            &shown,
            files::ReadProblem::Io(format!("it is not UTF-8 text (byte {})", e.utf8_error().valid_up_to())),
        ))
        .into()
    })
}

impl Problem {
    /// The problem `name` from `start` to `goal`, its blocks named `b1`, `b2`, ... (block `i`
    /// is `b{i+1}`), in the domain `blocksworld`, with the facts the competition's generator
    /// writes: `(arm-empty)`, and tower by tower from the top, `clear` of the top, the `on`
    /// facts and `on-table` of the bottom; the goal likewise, with `clear` facts only when
    /// it places every block (else they would say more than the goal's towers).
    pub fn new(name: &str, start: Towers, goal: TowerGoal) -> Result<Problem> {
        goal.check_blocks(start.blocks())?;
        if name.is_empty() || name.chars().any(|c| c.is_whitespace() || matches!(c, '(' | ')' | ';')) {
            return Err(
                PddlError::Unwritable(format!("{name:?} is not a PDDL name (no spaces, parentheses or ';')")).into(),
            );
        }
        let blocks: Vec<String> = (1..=start.blocks()).map(|i| format!("b{i}")).collect();
        let mut init = vec![Fact::ArmEmpty];
        init.extend(tower_facts(&start.towers(), true));
        let complete = (0..start.blocks()).all(|b| goal.is_named(b));
        let goal_facts = tower_facts(goal.towers(), complete);
        Ok(Problem {
            name: name.to_string(),
            domain: "blocksworld".into(),
            blocks,
            init,
            goal_facts,
            start,
            goal,
            actions: ActionNames::default(),
        })
    }

    /// Reads the problem file at `path`, at most [`MAX_PROBLEM_BYTES`]; every refusal names
    /// the file, the line and the problem. With no domain file, the problem's `(:domain
    /// NAME)` must name a Blocks World (a name holding `block`, as `blocksworld` and
    /// `BLOCKS` do) and its plans use the competition's action names.
    pub fn read(path: &Path) -> Result<Problem> {
        Problem::read_in(path, None)
    }

    /// Reads the problem file at `path` of the domain `domain` (if given): the problem
    /// must name that domain, and its plans use the domain's action names.
    pub fn read_in(path: &Path, domain: Option<&Domain>) -> Result<Problem> {
        let shown = path.display().to_string();
        let text = read_text(path, MAX_PROBLEM_BYTES, "a PDDL problem")?;
        Problem::parse_in(&text, &shown, domain)
    }

    /// The problem in `text` (named "the problem" in errors).
    pub fn parse(text: &str) -> Result<Problem> {
        Problem::parse_named(text, "the problem")
    }

    /// The problem in `text`, named `file` in errors.
    pub fn parse_named(text: &str, file: &str) -> Result<Problem> {
        Problem::parse_in(text, file, None)
    }

    /// The problem in `text`, named `file` in errors, of the domain `domain` if given
    /// ([`Problem::read_in`]).
    pub fn parse_in(text: &str, file: &str, domain: Option<&Domain>) -> Result<Problem> {
        let src = Source { file };
        let top = sexpr::parse(text, "problem").or_else(|(line, reason)| src.err(line, reason))?;
        let Node::List { items, line } = &top else {
            unreachable!("sexpr::parse returns a list")
        };
        if items.first().and_then(Node::key) != Some("define") {
            return src.err(*line, "a problem file starts (define (problem NAME) ...)");
        }
        let name = match items.get(1) {
            Some(Node::List { items: head, .. }) if head.first().and_then(Node::key) == Some("problem") => {
                match head.get(1) {
                    Some(Node::Name { text, .. }) if head.len() == 2 => text.clone(),
                    _ => return src.err(*line, "(problem NAME) takes one name"),
                }
            }
            Some(Node::List { items: head, line }) if head.first().and_then(Node::key) == Some("domain") => {
                return src.err(*line, "this is a domain file: give the problem file");
            }
            _ => return src.err(*line, "a problem file starts (define (problem NAME) ...)"),
        };
        let mut domain_name = None;
        let mut objects = None;
        let mut init = None;
        let mut goal = None;
        for section in &items[2..] {
            let Node::List { items: parts, line } = section else {
                return src.err(
                    section.line(),
                    format!("{} stands outside any section", section.shown()),
                );
            };
            let slot = match parts.first().and_then(Node::key) {
                Some(":domain") => &mut domain_name,
                Some(":objects") => &mut objects,
                Some(":init") => &mut init,
                Some(":goal") => &mut goal,
                Some(":requirements") => continue,
                Some(":metric") => {
                    check_metric(&src, section)?;
                    continue;
                }
                _ => {
                    return src.err(
                        *line,
                        format!(
                            "the section {} is not read: a Blocks World problem has :domain, :objects, :init, :goal and at most (:metric minimize (total-cost))",
                            section.shown()
                        ),
                    );
                }
            };
            if slot.is_some() {
                return src.err(*line, format!("a second {} section", parts[0].shown()));
            }
            *slot = Some((&parts[1..], *line));
        }
        let domain_name = match domain_name {
            Some(([Node::Name { text, .. }], at)) => {
                check_domain_name(&src, text, domain, at)?;
                text.clone()
            }
            Some((_, line)) => return src.err(line, "(:domain NAME) takes one name"),
            None => return src.err(*line, "the problem has no (:domain ...) section"),
        };
        let Some((objects, objects_line)) = objects else {
            return src.err(*line, "the problem has no (:objects ...) section");
        };
        let blocks = read_objects(&src, objects, objects_line)?;
        let Some((init, init_line)) = init else {
            return src.err(*line, "the problem has no (:init ...) section");
        };
        let Some((goal, goal_line)) = goal else {
            return src.err(*line, "the problem has no (:goal ...) section");
        };
        let init_facts = init
            .iter()
            .filter(|node| !is_initial_cost(node))
            .map(|node| read_fact(&src, &blocks, node, "init"))
            .collect::<Result<Vec<(Fact, usize)>>>()?;
        let goal_facts = match goal {
            [one] => read_goal(&src, &blocks, one)?,
            _ => return src.err(goal_line, "(:goal ...) takes one condition, e.g. (and (on b1 b2) ...)"),
        };
        let names = blocks.names;
        let start = read_start(&src, &names, &init_facts, init_line)?;
        let tower_goal = read_goal_towers(&src, &names, &goal_facts, goal_line)?;
        Ok(Problem {
            name,
            domain: domain_name,
            blocks: names,
            init: init_facts.into_iter().map(|(f, _)| f).collect(),
            goal_facts: goal_facts.into_iter().map(|(f, _)| f).collect(),
            start,
            goal: tower_goal,
            actions: domain.map_or_else(ActionNames::default, |d| d.actions().clone()),
        })
    }

    /// The problem's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The domain it names (`blocksworld` in the competition's files).
    pub fn domain(&self) -> &str {
        &self.domain
    }

    /// The blocks' names as the file spells them; block `i` is `block_names()[i]`.
    pub fn block_names(&self) -> &[String] {
        &self.blocks
    }

    /// The initial state's facts as the file states them.
    pub fn init_facts(&self) -> &[Fact] {
        &self.init
    }

    /// The goal's facts as the file states them.
    pub fn goal_facts(&self) -> &[Fact] {
        &self.goal_facts
    }

    /// The initial state as towers.
    pub fn start(&self) -> &Towers {
        &self.start
    }

    /// The goal as towers (blocks it does not place are free).
    pub fn goal(&self) -> &TowerGoal {
        &self.goal
    }

    /// The names its plans give the actions: its domain file's, or the competition's.
    pub fn action_names(&self) -> &ActionNames {
        &self.actions
    }
}

/// The problem's `(:domain NAME)`: the domain file's name if one is given, else a Blocks
/// World's (a name holding `block`); anything else is another domain, not read as this one.
fn check_domain_name(src: &Source<'_>, name: &str, domain: Option<&Domain>, line: usize) -> Result<()> {
    match domain {
        Some(d) if !d.name().eq_ignore_ascii_case(name) => src.err(
            line,
            format!("the problem is of the domain {name}, but the domain file defines {}", d.name()),
        ),
        Some(_) => Ok(()),
        None if name.to_lowercase().contains("block") => Ok(()),
        None => src.err(
            line,
            format!(
                "(:domain {name}) is not the Blocks World, the one domain blockstack plans; if it is the Blocks World under another name, give its domain file with it"
            ),
        ),
    }
}

/// `(:metric minimize (total-cost))`: the Blocks World's actions cost 1 each, so the plan
/// with the fewest actions is the cheapest and the metric changes nothing. Any other
/// metric is refused.
fn check_metric(src: &Source<'_>, section: &Node) -> Result<()> {
    let Node::List { items, line } = section else {
        unreachable!("a section is a list")
    };
    let total_cost =
        |n: &Node| matches!(n, Node::List { items, .. } if items.len() == 1 && items[0].key() == Some("total-cost"));
    match items.as_slice() {
        [_, how, cost] if how.key() == Some("minimize") && total_cost(cost) => Ok(()),
        _ => src.err(
            *line,
            format!(
                "the metric {} is not read: blockstack minimizes the number of actions, (:metric minimize (total-cost)) of unit costs",
                section.shown()
            ),
        ),
    }
}

/// `(= (total-cost) N)` in the init: the starting cost of a problem with a metric, which
/// says nothing of the blocks.
fn is_initial_cost(node: &Node) -> bool {
    matches!(node, Node::List { items, .. }
        if items.len() == 3 && items[0].key() == Some("=")
            && matches!(&items[1], Node::List { items, .. } if items.len() == 1 && items[0].key() == Some("total-cost")))
}

/// The facts of `towers` (each bottom to top), tower by tower from the top: `clear` of
/// the top if `clear`, the `on` facts, `on-table` of the bottom.
fn tower_facts(towers: &[Vec<usize>], clear: bool) -> Vec<Fact> {
    let mut facts = Vec::new();
    for tower in towers {
        if clear {
            facts.push(Fact::Clear(tower[tower.len() - 1]));
        }
        for pair in tower.windows(2).rev() {
            facts.push(Fact::On(pair[1], pair[0]));
        }
        facts.push(Fact::OnTable(tower[0]));
    }
    facts
}

/// The declared blocks: names as written, and each lower-cased name's index.
struct Objects {
    names: Vec<String>,
    index: HashMap<String, usize>,
}

/// The objects: names, with `- TYPE` after a group.
fn read_objects(src: &Source<'_>, nodes: &[Node], line: usize) -> Result<Objects> {
    let mut names: Vec<String> = Vec::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut lines: Vec<usize> = Vec::new();
    let mut i = 0;
    while i < nodes.len() {
        match &nodes[i] {
            Node::Name { key, .. } if key == "-" => {
                // A type, or several (`(either block thing)`): the blocks are blocks whatever
                // their type says.
                let typed = match nodes.get(i + 1) {
                    Some(Node::Name { .. }) => true,
                    Some(Node::List { items, .. }) => {
                        items.first().and_then(Node::key) == Some("either")
                            && items.len() > 1
                            && items[1..].iter().all(|t| t.key().is_some())
                    }
                    None => false,
                };
                if !typed {
                    return src.err(
                        nodes[i].line(),
                        "'-' in :objects must be followed by a type name or (either TYPE ...)",
                    );
                }
                i += 2;
                continue;
            }
            Node::Name { key, text, line } => {
                if let Some(&first) = index.get(key) {
                    let first = lines[first];
                    return src.err(
                        *line,
                        format!("object {text} is declared twice (first on line {first})"),
                    );
                }
                index.insert(key.clone(), names.len());
                names.push(text.clone());
                lines.push(*line);
            }
            other => return src.err(other.line(), format!("{} in :objects is not a name", other.shown())),
        }
        i += 1;
    }
    if names.is_empty() {
        return src.err(line, "the problem declares no blocks in :objects");
    }
    Ok(Objects { names, index })
}

/// The index of the block `node` names.
fn block_of(src: &Source<'_>, blocks: &Objects, node: &Node, fact: &Node) -> Result<usize> {
    match node {
        Node::Name { key, text, line } => match blocks.index.get(key) {
            Some(&i) => Ok(i),
            None => src.err(
                *line,
                format!("{} names {text}, which :objects does not declare", fact.shown()),
            ),
        },
        other => src.err(
            other.line(),
            format!("{} in {} is not a block name", other.shown(), fact.shown()),
        ),
    }
}

/// One fact of the `part` (init or goal), with its line.
fn read_fact(src: &Source<'_>, blocks: &Objects, node: &Node, part: &str) -> Result<(Fact, usize)> {
    let line = node.line();
    let Node::List { items, .. } = node else {
        return src.err(
            line,
            format!("{} in the {part} is not a fact such as (on b1 b2)", node.shown()),
        );
    };
    let Some(predicate) = items.first().and_then(Node::key) else {
        return src.err(
            line,
            format!("{} in the {part} is not a fact such as (on b1 b2)", node.shown()),
        );
    };
    let fact_of = match Predicate::of_name(predicate) {
        Some(p) => p,
        None if matches!(predicate, "not" | "or" | "imply" | "exists" | "forall" | "when" | "=") => {
            return src.err(
                line,
                format!(
                    "{} in the {part}: a Blocks World {part} is a list of facts ({PREDICATES})",
                    node.shown()
                ),
            );
        }
        None => {
            return src.err(
                line,
                format!(
                    "unknown predicate {predicate} in {}: the 4-operator Blocks World has {PREDICATES}",
                    node.shown()
                ),
            );
        }
    };
    let arity = fact_of.arity();
    if items.len() != arity + 1 {
        return src.err(
            line,
            format!("{} takes {arity} block(s), not {}", node.shown(), items.len() - 1),
        );
    }
    let args = items[1..]
        .iter()
        .map(|arg| block_of(src, blocks, arg, node))
        .collect::<Result<Vec<usize>>>()?;
    Ok((fact_of.fact(&args), line))
}

/// The goal's facts: one fact, or `(and ...)` of facts (nested `and`s flattened).
fn read_goal(src: &Source<'_>, blocks: &Objects, node: &Node) -> Result<Vec<(Fact, usize)>> {
    let mut facts = Vec::new();
    let mut todo = vec![node];
    while let Some(node) = todo.pop() {
        match node {
            Node::List { items, .. } if items.first().and_then(Node::key) == Some("and") => {
                todo.extend(items[1..].iter().rev());
            }
            _ => facts.push(read_fact(src, blocks, node, "goal")?),
        }
    }
    Ok(facts)
}

/// Each block's support and the block on each, from `on` / `on-table` facts; refuses a
/// block placed twice, two blocks on one, a block on itself. `None` below: not placed.
struct Supports {
    /// `Some(None)`: the table; `Some(Some(y))`: on `y`; with the fact's line.
    below: Vec<Option<(Option<usize>, usize)>>,
    /// The block on each, with the line.
    above: Vec<Option<(usize, usize)>>,
    /// The blocks on the table, in the order of their facts.
    bottoms: Vec<usize>,
}

fn supports(src: &Source<'_>, names: &[String], facts: &[(Fact, usize)], part: &str) -> Result<Supports> {
    let n = names.len();
    let mut s = Supports {
        below: vec![None; n],
        above: vec![None; n],
        bottoms: Vec::new(),
    };
    let show = |support: Option<usize>, x: usize| match support {
        None => format!("(on-table {})", names[x]),
        Some(y) => format!("(on {} {})", names[x], names[y]),
    };
    for &(fact, line) in facts {
        let (x, support) = match fact {
            Fact::OnTable(x) => (x, None),
            Fact::On(x, y) => (x, Some(y)),
            _ => continue,
        };
        if support == Some(x) {
            return src.err(line, format!("{}: a block cannot stand on itself", show(support, x)));
        }
        match s.below[x] {
            Some((old, _)) if old == support => continue,
            Some((old, first)) => {
                return src.err(
                    line,
                    format!(
                        "block {} is placed twice in the {part}: {} (line {first}) and {}",
                        names[x],
                        show(old, x),
                        show(support, x)
                    ),
                );
            }
            None => {
                s.below[x] = Some((support, line));
                if support.is_none() {
                    s.bottoms.push(x);
                }
            }
        }
        if let Some(y) = support {
            if let Some((other, first)) = s.above[y] {
                return src.err(
                    line,
                    format!(
                        "two blocks stand on {} in the {part}: {} (line {first}) and {}",
                        names[y], names[other], names[x]
                    ),
                );
            }
            s.above[y] = Some((x, line));
        }
    }
    Ok(s)
}

/// The towers the supports make, each bottom to top, from the placed blocks that reach the
/// table; `Err((block, cycle))` if following `on` from `block` comes back to it, or
/// `Err((block, vec![]))` if it reaches a block placed nowhere.
fn chains(s: &Supports, placed: impl Fn(usize) -> bool) -> std::result::Result<Vec<Vec<usize>>, (usize, Vec<usize>)> {
    let n = s.below.len();
    // 0: not seen, 1: on the walk now, 2: reaches the table.
    let mut state = vec![0u8; n];
    for b in (0..n).filter(|&b| placed(b)) {
        let mut walk = Vec::new();
        let mut v = b;
        loop {
            match state[v] {
                2 => break,
                1 => {
                    let from = walk.iter().position(|&w| w == v).expect("v is on the walk");
                    return Err((v, walk[from..].to_vec()));
                }
                _ => {}
            }
            state[v] = 1;
            walk.push(v);
            match s.below[v] {
                Some((None, _)) => break,
                Some((Some(y), _)) => v = y,
                None => return Err((v, Vec::new())),
            }
        }
        for w in walk {
            state[w] = 2;
        }
    }
    let mut towers = Vec::new();
    // In the order of the on-table facts, so that a problem written reads back the same.
    for &bottom in &s.bottoms {
        let mut tower = vec![bottom];
        while let Some((up, _)) = s.above[tower[tower.len() - 1]] {
            tower.push(up);
        }
        towers.push(tower);
    }
    Ok(towers)
}

/// `b1 on b2 on b3 on b1`.
fn cycle_text(names: &[String], cycle: &[usize]) -> String {
    let mut parts: Vec<&str> = cycle.iter().map(|&b| names[b].as_str()).collect();
    parts.push(&names[cycle[0]]);
    parts.join(" on ")
}

/// The initial state: every block placed once, on the table or on one block, no cycle,
/// `clear` exactly where nothing stands, the arm empty.
fn read_start(src: &Source<'_>, names: &[String], facts: &[(Fact, usize)], line: usize) -> Result<Towers> {
    if let Some(&(Fact::Holding(x), at)) = facts.iter().find(|(f, _)| matches!(f, Fact::Holding(_))) {
        return src.err(
            at,
            format!(
                "the init holds {}: blockstack plans from a state with the arm empty (put it on the table in the file)",
                names[x]
            ),
        );
    }
    if !facts.iter().any(|(f, _)| *f == Fact::ArmEmpty) {
        return src.err(line, "the init lacks (arm-empty): with nothing held the arm is empty");
    }
    let s = supports(src, names, facts, "init")?;
    let towers = match chains(&s, |_| true) {
        Ok(towers) => towers,
        Err((b, cycle)) if cycle.is_empty() => {
            return src.err(
                line,
                format!(
                    "the init does not say where {} stands: give (on-table {}) or (on {} ...)",
                    names[b], names[b], names[b]
                ),
            );
        }
        Err((b, cycle)) => {
            let at = s.below[b].map_or(line, |(_, l)| l);
            return src.err(
                at,
                format!("the init's on facts form a cycle: {}", cycle_text(names, &cycle)),
            );
        }
    };
    let mut clear = vec![None; names.len()];
    for &(fact, at) in facts {
        if let Fact::Clear(x) = fact {
            clear[x].get_or_insert(at);
        }
    }
    for (b, name) in names.iter().enumerate() {
        match (clear[b], s.above[b]) {
            (Some(at), Some((on, _))) => {
                return src.err(
                    at,
                    format!("the init says (clear {name}) but {} stands on it", names[on]),
                );
            }
            (None, None) => {
                return src.err(
                    line,
                    format!("nothing stands on {name} in the init, but the init lacks (clear {name})"),
                );
            }
            _ => {}
        }
    }
    Towers::new(&towers)
}

/// The goal as towers: each placed block's support; refuses a block placed twice, a cycle,
/// a tower whose bottom is not said to stand on the table (bare `on` facts), a `clear`
/// the towers do not imply, and `holding`.
fn read_goal_towers(src: &Source<'_>, names: &[String], facts: &[(Fact, usize)], line: usize) -> Result<TowerGoal> {
    if let Some(&(Fact::Holding(x), at)) = facts.iter().find(|(f, _)| matches!(f, Fact::Holding(_))) {
        return src.err(
            at,
            format!("the goal holds {}: blockstack's goals leave the arm empty", names[x]),
        );
    }
    let s = supports(src, names, facts, "goal")?;
    let towers = match chains(&s, |b| s.below[b].is_some()) {
        Ok(towers) => towers,
        Err((b, cycle)) if cycle.is_empty() => {
            // b is a support in the goal, placed nowhere itself.
            let (x, at) = s.above[b].expect("only a support is reached unplaced");
            return src.err(
                at,
                format!(
                    "the goal puts {} on {} but does not say what {} stands on; blockstack reads a goal's towers \
                     from the table up, so add (on-table {}) or (on {} ...) (a goal of bare on facts, as PDDLGym \
                     writes, is not read)",
                    names[x], names[b], names[b], names[b], names[b]
                ),
            );
        }
        Err((b, cycle)) => {
            let at = s.below[b].map_or(line, |(_, l)| l);
            return src.err(
                at,
                format!("the goal's on facts form a cycle: {}", cycle_text(names, &cycle)),
            );
        }
    };
    let complete = s.below.iter().all(Option::is_some);
    for &(fact, at) in facts {
        if let Fact::Clear(x) = fact {
            if let Some((on, _)) = s.above[x] {
                return src.err(
                    at,
                    format!("the goal says (clear {}) and puts {} on it", names[x], names[on]),
                );
            }
            if !complete {
                return src.err(
                    at,
                    format!(
                        "the goal says (clear {}) but does not place every block, so its towers do not imply it; \
                         blockstack's goals say what blocks stand on, and a tower may carry free blocks",
                        names[x]
                    ),
                );
            }
        }
    }
    TowerGoal::new(&towers)
}

impl fmt::Display for Problem {
    /// The problem as PDDL, in the competition generator's layout; reading it back gives the
    /// same problem.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "(define (problem {})", self.name)?;
        writeln!(f, " (:domain {})", self.domain)?;
        writeln!(f, " (:objects {} - object)", self.blocks.join(" "))?;
        f.write_str(" (:init")?;
        for fact in &self.init {
            write!(f, "\n    {}", fact.to_pddl(&self.blocks))?;
        }
        f.write_str(")\n (:goal (and")?;
        for fact in &self.goal_facts {
            write!(f, "\n    {}", fact.to_pddl(&self.blocks))?;
        }
        f.write_str(")))\n")
    }
}
