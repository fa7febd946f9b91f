//! A domain file: the 4-operator Blocks World, checked action by action, and the names its
//! plans use.
//!
//! # Why read the domain
//!
//! A planner takes a domain and a problem, and its plan names the domain's actions. The
//! Blocks World is written in two spellings: `pickup`/`putdown` (the 2023 competition's
//! learning track, the `pddl-generators`) and `pick-up`/`put-down` (the 2000 competition,
//! PDDLGym, most textbooks), often with `ontable`/`handempty` for `on-table`/`arm-empty`.
//! A plan printed in the wrong spelling fails the validator of whoever gave the domain, so
//! the names of the plan are taken from the file ([`ActionNames`]).
//!
//! # What is accepted
//!
//! blockstack plans one domain, so a domain file is accepted only if it *is* that domain:
//! four actions, one for each of [`Operator`], whose parameters, precondition and effects
//! are, up to the names of the parameters and the order of the facts, the ones below
//! ([`Action::conditions`](super::Action::conditions) is the one home of these rules, which
//! the plan replay applies too):
//!
//! | action | parameters | precondition | adds | deletes |
//! |---|---|---|---|---|
//! | `pickup` | `?x` | `clear x`, `on-table x`, `arm-empty` | `holding x` | the precondition |
//! | `putdown` | `?x` | `holding x` | `clear x`, `arm-empty`, `on-table x` | `holding x` |
//! | `stack` | `?x ?y` | `clear y`, `holding x` | `arm-empty`, `clear x`, `on x y` | the precondition |
//! | `unstack` | `?x ?y` | `on x y`, `clear x`, `arm-empty` | `holding x`, `clear y` | the precondition |
//!
//! Types (`:types`, `?x - block`) and `(:requirements :strips :typing)` are read and
//! ignored. Anything else is refused in one line naming it: another action or predicate,
//! a precondition or effect that differs (naming the fact), a requirement such as
//! `:action-costs`, a section such as `:functions` or `:constants`.

use std::collections::HashSet;
use std::path::Path;

use crate::error::Result;

use super::sexpr::{self, Node, Source};
use super::vocabulary::{ActionNames, Fact, Operator, Predicate};

/// The largest domain file read: 1 MiB (the domain is under 2 KiB).
pub const MAX_DOMAIN_BYTES: u64 = 1 << 20;

/// A checked 4-operator Blocks World domain: its name and the names of its actions.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Domain {
    name: String,
    actions: ActionNames,
}

/// What the domain is, for refusals.
const SUPPORTED: &str =
    "blockstack plans the 4-operator Blocks World only (pickup/pick-up, putdown/put-down, stack, unstack)";

impl Domain {
    /// Reads the domain file at `path`, at most [`MAX_DOMAIN_BYTES`]; every refusal names
    /// the file, the line and what is not supported.
    pub fn read(path: &Path) -> Result<Domain> {
        let shown = path.display().to_string();
        let text = super::problem::read_text(path, MAX_DOMAIN_BYTES, "a PDDL domain")?;
        Domain::parse_named(&text, &shown)
    }

    /// The domain in `text` (named "the domain" in errors).
    pub fn parse(text: &str) -> Result<Domain> {
        Domain::parse_named(text, "the domain")
    }

    /// The domain in `text`, named `file` in errors.
    pub fn parse_named(text: &str, file: &str) -> Result<Domain> {
        let src = Source { file };
        let top = sexpr::parse(text, "domain").or_else(|(line, reason)| src.err(line, reason))?;
        let Node::List { items, line } = &top else {
            unreachable!("sexpr::parse returns a list")
        };
        let line = *line;
        if items.first().and_then(Node::key) != Some("define") {
            return src.err(line, "a domain file starts (define (domain NAME) ...)");
        }
        let name = match items.get(1) {
            Some(Node::List { items: head, line }) if head.first().and_then(Node::key) == Some("domain") => {
                match head.as_slice() {
                    [_, Node::Name { text, .. }] => text.clone(),
                    _ => return src.err(*line, "(domain NAME) takes one name"),
                }
            }
            Some(Node::List { items: head, line }) if head.first().and_then(Node::key) == Some("problem") => {
                return src.err(*line, "this is a problem file: give the domain file");
            }
            _ => return src.err(line, "a domain file starts (define (domain NAME) ...)"),
        };
        let mut actions: [Option<(String, usize)>; 4] = Default::default();
        for section in &items[2..] {
            let Node::List { items: parts, line } = section else {
                return src.err(
                    section.line(),
                    format!("{} stands outside any section", section.shown()),
                );
            };
            match parts.first().and_then(Node::key) {
                Some(":requirements") => check_requirements(&src, &parts[1..])?,
                Some(":types") => {}
                Some(":predicates") => check_predicates(&src, &parts[1..])?,
                Some(":action") => {
                    let (op, written) = check_action(&src, parts, *line)?;
                    if let Some((_, first)) = &actions[op as usize] {
                        return src.err(
                            *line,
                            format!("a second {written} action (the first is on line {first})"),
                        );
                    }
                    actions[op as usize] = Some((written, *line));
                }
                _ => {
                    return src.err(
                        *line,
                        format!("the section {} is not supported: {SUPPORTED}", section.shown()),
                    );
                }
            }
        }
        let mut names = ActionNames::default();
        for op in Operator::ALL {
            match &actions[op as usize] {
                Some((written, _)) => names.0[op as usize] = written.clone(),
                None => {
                    return src.err(
                        line,
                        format!("the domain has no {} action: {SUPPORTED}", op.spellings().join("/")),
                    );
                }
            }
        }
        Ok(Domain { name, actions: names })
    }

    /// The domain's name, as written.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The names of its actions, as written.
    pub fn actions(&self) -> &ActionNames {
        &self.actions
    }
}

/// `:strips` and `:typing`; anything else names what it needs that is not planned here.
fn check_requirements(src: &Source<'_>, flags: &[Node]) -> Result<()> {
    for flag in flags {
        if !matches!(flag.key(), Some(":strips" | ":typing")) {
            return src.err(
                flag.line(),
                format!("the requirement {} is not supported: the 4-operator Blocks World needs :strips (and :typing at most)", flag.shown()),
            );
        }
    }
    Ok(())
}

/// The names of the predicates, in either spelling, for messages.
const PREDICATES: &str = "on, on-table (or ontable), clear, arm-empty (or handempty) and holding";

/// Every declared predicate is one of the domain's, with its arity.
fn check_predicates(src: &Source<'_>, declared: &[Node]) -> Result<()> {
    for node in declared {
        let predicate = match node {
            Node::List { items, .. } => items
                .first()
                .and_then(Node::key)
                .and_then(Predicate::of_name)
                .map(|p| (p, items)),
            Node::Name { .. } => None,
        };
        let Some((predicate, items)) = predicate else {
            return src.err(
                node.line(),
                format!(
                    "the predicate {} is not one of the 4-operator Blocks World's: {PREDICATES}",
                    node.shown()
                ),
            );
        };
        let params = parameters(src, &items[1..], node)?;
        if params.len() != predicate.arity() {
            return src.err(
                node.line(),
                format!(
                    "{} takes {} parameter(s) in the Blocks World, not {}",
                    node.shown(),
                    predicate.arity(),
                    params.len()
                ),
            );
        }
    }
    Ok(())
}

/// The variables of a typed list `?x ?y - block ?z`, types skipped.
fn parameters(src: &Source<'_>, nodes: &[Node], whole: &Node) -> Result<Vec<String>> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < nodes.len() {
        match &nodes[i] {
            Node::Name { key, .. } if key == "-" => {
                // A type name or (either ...): types do not change the Blocks World.
                if nodes.get(i + 1).is_none() {
                    return src.err(
                        nodes[i].line(),
                        format!("'-' in {} must be followed by a type", whole.shown()),
                    );
                }
                i += 2;
                continue;
            }
            Node::Name { key, .. } if key.starts_with('?') => out.push(key.clone()),
            other => {
                return src.err(
                    other.line(),
                    format!("{} in {} is not a parameter such as ?x", other.shown(), whole.shown()),
                );
            }
        }
        i += 1;
    }
    Ok(out)
}

/// One `(:action NAME :parameters (...) :precondition ... :effect ...)`: which operator it
/// is, as written, if its parameters, precondition and effects are the operator's.
fn check_action(src: &Source<'_>, parts: &[Node], line: usize) -> Result<(Operator, String)> {
    let (op, written) = match parts.get(1) {
        Some(Node::Name { key, text, .. }) => match Operator::of_name(key) {
            Some(op) => (op, text.clone()),
            None => return src.err(line, format!("the action {text} is not supported: {SUPPORTED}")),
        },
        _ => return src.err(line, "(:action NAME ...) takes a name"),
    };
    let mut params = None;
    let mut precondition = None;
    let mut effect = None;
    let mut rest = parts[2..].iter();
    while let Some(key) = rest.next() {
        let slot = match key.key() {
            Some(":parameters") => &mut params,
            Some(":precondition") => &mut precondition,
            Some(":effect") => &mut effect,
            _ => {
                return src.err(
                    key.line(),
                    format!("{} in the action {written} is not supported: an action has :parameters, :precondition and :effect", key.shown()),
                );
            }
        };
        let Some(value) = rest.next() else {
            return src.err(
                key.line(),
                format!("{} in the action {written} has no value", key.shown()),
            );
        };
        *slot = Some(value);
    }
    let Some(params @ Node::List { items, .. }) = params else {
        return src.err(line, format!("the action {written} has no :parameters list"));
    };
    let vars = parameters(src, items, params)?;
    if vars.len() != op.arity() {
        return src.err(
            params.line(),
            format!(
                "the action {written} takes {} parameter(s) in the Blocks World, not {}",
                op.arity(),
                vars.len()
            ),
        );
    }
    let atoms = |node: Option<&Node>, part: &str| -> Result<(Vec<Fact>, Vec<Fact>)> {
        let mut pos = Vec::new();
        let mut neg = Vec::new();
        if let Some(node) = node {
            read_conjunction(src, &vars, node, &written, part, &mut pos, &mut neg)?;
        }
        Ok((pos, neg))
    };
    let (pre, pre_neg) = atoms(precondition, "precondition")?;
    if let Some(&f) = pre_neg.first() {
        return src.err(
            line,
            format!(
                "the action {written}'s precondition negates {}: {SUPPORTED}",
                shown(f, &vars)
            ),
        );
    }
    let (add, del) = atoms(effect, "effect")?;
    let expected = op.schema().conditions();
    for (part, (lacks, holds), got, want) in [
        ("precondition", ("lacks", "holds"), &pre, &expected.pre),
        ("added facts", ("lack", "hold"), &add, &expected.add),
        ("deleted facts", ("lack", "hold"), &del, &expected.del),
    ] {
        let got: HashSet<Fact> = got.iter().copied().collect();
        let want: HashSet<Fact> = want.iter().copied().collect();
        if let Some(&f) = want.iter().find(|f| !got.contains(f)) {
            return src.err(
                line,
                format!("the action {written}'s {part} {lacks} {}: {SUPPORTED}", shown(f, &vars)),
            );
        }
        if let Some(&f) = got.iter().find(|f| !want.contains(f)) {
            return src.err(
                line,
                format!(
                    "the action {written}'s {part} {holds} {}, which the Blocks World's do not: {SUPPORTED}",
                    shown(f, &vars)
                ),
            );
        }
    }
    Ok((op, written))
}

/// A schema's fact with the action's own parameter names: `(on ?ob ?underob)`.
fn shown(fact: Fact, vars: &[String]) -> String {
    fact.to_pddl(vars)
}

/// The atoms of `node`, an atom or `(and ...)` of atoms and `(not atom)`s, over the
/// parameters `vars` (parameter `i` is block `i` of the facts).
fn read_conjunction(
    src: &Source<'_>,
    vars: &[String],
    node: &Node,
    action: &str,
    part: &str,
    pos: &mut Vec<Fact>,
    neg: &mut Vec<Fact>,
) -> Result<()> {
    let mut todo = vec![(node, false)];
    while let Some((node, negated)) = todo.pop() {
        let Node::List { items, line } = node else {
            return src.err(
                node.line(),
                format!("{} in the action {action}'s {part} is not a fact", node.shown()),
            );
        };
        match items.first().and_then(Node::key) {
            Some("and") if !negated => todo.extend(items[1..].iter().rev().map(|n| (n, false))),
            Some("not") if !negated && items.len() == 2 => todo.push((&items[1], true)),
            Some(name) => {
                let fact = match Predicate::of_name(name) {
                    Some(p) if items.len() == p.arity() + 1 => {
                        let mut args = Vec::new();
                        for arg in &items[1..] {
                            match arg.key().and_then(|k| vars.iter().position(|v| v == k)) {
                                Some(i) => args.push(i),
                                None => {
                                    return src.err(
                                        *line,
                                        format!("{} in the action {action}'s {part} names {}, which is not a parameter: {SUPPORTED}", node.shown(), arg.shown()),
                                    );
                                }
                            }
                        }
                        p.fact(&args)
                    }
                    _ => {
                        return src.err(
                            *line,
                            format!(
                                "{} in the action {action}'s {part} is not a fact of the Blocks World ({PREDICATES})",
                                node.shown()
                            ),
                        );
                    }
                };
                if negated { neg.push(fact) } else { pos.push(fact) }
            }
            None => {
                return src.err(
                    *line,
                    format!("{} in the action {action}'s {part} is not a fact", node.shown()),
                );
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const IPC: &str = "(define (domain blocksworld) (:requirements :strips)
      (:predicates (clear ?x) (on-table ?x) (arm-empty) (holding ?x) (on ?x ?y))
      (:action pickup :parameters (?ob)
        :precondition (and (clear ?ob) (on-table ?ob) (arm-empty))
        :effect (and (holding ?ob) (not (clear ?ob)) (not (on-table ?ob)) (not (arm-empty))))
      (:action putdown :parameters (?ob) :precondition (holding ?ob)
        :effect (and (clear ?ob) (arm-empty) (on-table ?ob) (not (holding ?ob))))
      (:action stack :parameters (?ob ?underob)
        :precondition (and (clear ?underob) (holding ?ob))
        :effect (and (arm-empty) (clear ?ob) (on ?ob ?underob) (not (clear ?underob)) (not (holding ?ob))))
      (:action unstack :parameters (?ob ?underob)
        :precondition (and (on ?ob ?underob) (clear ?ob) (arm-empty))
        :effect (and (holding ?ob) (clear ?underob) (not (on ?ob ?underob)) (not (clear ?ob)) (not (arm-empty)))))";

    #[test]
    fn the_competitions_domain_is_read_with_its_names() {
        let d = Domain::parse(IPC).unwrap();
        assert_eq!(d.name(), "blocksworld");
        assert_eq!(d.actions(), &ActionNames::default());
    }

    #[test]
    fn the_other_spelling_gives_its_names_to_the_plan() {
        let text = IPC
            .replace("pickup", "pick-up")
            .replace("putdown", "PUT-DOWN")
            .replace("on-table", "ontable")
            .replace("arm-empty", "handempty")
            .replace("(?ob ?underob)", "(?x - block ?y - block)")
            .replace("?underob", "?y")
            .replace("?ob", "?x");
        let d = Domain::parse(&text).unwrap();
        assert_eq!(d.actions().of(Operator::Pickup), "pick-up");
        assert_eq!(d.actions().of(Operator::Putdown), "PUT-DOWN");
    }

    #[test]
    fn anything_else_is_refused_naming_it() {
        let cases = [
            (
                IPC.replace(
                    "(not (arm-empty))))\n      (:action putdown",
                    "))\n      (:action putdown",
                ),
                "pickup's deleted facts lack (arm-empty)",
            ),
            (
                IPC.replace(
                    "(holding ?ob) (not (clear ?ob))",
                    "(holding ?ob) (on ?ob ?ob) (not (clear ?ob))",
                ),
                "pickup's added facts hold (on ?ob ?ob)",
            ),
            (
                IPC.replace("(:action unstack", "(:action fly"),
                "the action fly is not supported",
            ),
            (
                IPC.replace(":strips", ":strips :action-costs"),
                "the requirement :action-costs is not supported",
            ),
            (
                IPC.replace("(arm-empty) (holding ?x)", "(arm-empty) (holding ?x) (at ?x)"),
                "the predicate (at ?x) is not one of",
            ),
            (
                IPC.replace("(:requirements :strips)", "(:functions (total-cost))"),
                "the section (:functions (total-cost)) is not supported",
            ),
            (
                IPC.replace("(domain blocksworld)", "(problem p)"),
                "this is a problem file",
            ),
            (
                IPC.replace("(on ?ob ?underob) (clear ?ob)", "(clear ?ob)"),
                "unstack's precondition lacks (on ?ob ?underob)",
            ),
        ];
        for (text, expect) in cases {
            let err = Domain::parse(&text).unwrap_err().to_string();
            assert!(err.contains(expect), "got {err}\nexpected {expect}");
            assert!(!err.contains('\n'), "{err}");
        }
        let without_unstack = format!("{})", &IPC[..IPC.find("(:action unstack").unwrap()]);
        let err = Domain::parse(&without_unstack).unwrap_err().to_string();
        assert!(err.contains("the domain has no unstack action"), "{err}");
    }
}
