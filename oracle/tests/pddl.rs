//! PDDL problems and plans (`oracle::pddl`): round trips of generated problems of both
//! shapes (uniform, and the competition generator's), plans checked by replaying their
//! actions over the problem's facts, and the corpus of bad files, each refused in one line
//! naming its problem.

use std::path::{Path, PathBuf};

use oracle::OracleError;
use oracle::pddl::{self, Action, Fact, PddlError, Problem};
use oracle::towers::{ExactMoves, NearOptimal, TowerGoal, Towers, ipc_state, random_goal, random_state};
use proptest::prelude::*;

fn corpus(kind: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/pddl_files")
        .join(kind);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "pddl"))
        .collect();
    files.sort();
    files
}

/// A problem of `n` blocks: a start and a complete goal of the given shape.
fn problem(n: usize, ipc: bool, seed: u64) -> Problem {
    let (start, goal) = if ipc {
        (ipc_state(n, seed), ipc_state(n, seed ^ 0x9e37))
    } else {
        (random_state(n, seed), random_state(n, seed ^ 0x9e37))
    };
    Problem::new("p", start, TowerGoal::new(&goal.towers()).unwrap()).unwrap()
}

#[test]
fn every_bad_file_is_refused_in_one_line_naming_its_problem() {
    let files = corpus("bad");
    assert!(files.len() >= 20, "{files:?}");
    for path in files {
        let text = std::fs::read(&path).unwrap();
        let first = String::from_utf8_lossy(&text).lines().next().unwrap().to_string();
        let expect = first
            .strip_prefix("; expect: ")
            .unwrap_or_else(|| panic!("{}: no '; expect:' line", path.display()));
        let err = Problem::read(&path).expect_err(&path.display().to_string()).to_string();
        assert!(
            err.contains(expect),
            "{}:\n  got      {err}\n  expected {expect}",
            path.display()
        );
        assert!(
            err.starts_with(&path.display().to_string()) || err.starts_with("cannot read"),
            "{err}"
        );
        assert!(!err.contains('\n'), "{err}");
    }
}

#[test]
fn a_huge_file_is_refused_before_it_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("huge.pddl");
    let file = std::fs::File::create(&path).unwrap();
    file.set_len(1 << 30).unwrap();
    let err = Problem::read(&path).unwrap_err();
    assert!(matches!(&err, OracleError::Pddl(PddlError::File(_))), "{err:?}");
    assert!(
        err.to_string()
            .contains("larger than 64 MiB, the most a PDDL problem can be"),
        "{err}"
    );
}

#[test]
fn legal_pddl_other_tools_write_is_read() {
    let files = corpus("good");
    let named = |name: &str| files.iter().find(|f| f.ends_with(name)).unwrap().clone();
    let upper = Problem::read(&named("upper_case.pddl")).unwrap();
    assert_eq!(upper.name(), "BLOCKS-3-0");
    assert_eq!(upper.block_names(), ["C", "A", "B"]);
    // A on B; C alone. Goal: C on B on A.
    assert_eq!(upper.start().towers(), vec![vec![0], vec![2, 1]]);
    assert_eq!(upper.goal().towers(), [vec![1, 2, 0]]);
    let plan = NearOptimal::new().plan(upper.start(), upper.goal()).unwrap();
    let actions = pddl::actions(upper.start(), &plan).unwrap();
    assert_eq!(
        upper.plan_text(&actions),
        "(unstack A B)\n(putdown A)\n(pickup B)\n(stack B A)\n(pickup C)\n(stack C B)\n; cost = 6 (unit cost)\n"
    );
    upper.replay(&actions).unwrap();

    let partial = Problem::read(&named("partial_goal.pddl")).unwrap();
    // b1 on b2 on b3; b4. Goal: b2 on b1 on the table; b3 and b4 free.
    assert!(!partial.goal().is_named(2) && !partial.goal().is_named(3));
    let exact = ExactMoves::new().solve(partial.start(), partial.goal()).unwrap();
    assert_eq!(exact.len(), 2);
    partial
        .replay(&pddl::actions(partial.start(), &exact).unwrap())
        .unwrap();

    // ontable and handempty, (either ...) types, a unit-cost metric and its initial cost.
    let other = Problem::read(&named("other_tools.pddl")).unwrap();
    assert_eq!(other.block_names(), ["a", "b"]);
    assert_eq!(other.start().towers(), vec![vec![0, 1]]);
    assert_eq!(other.goal().towers(), [vec![1, 0]]);
    assert!(other.init_facts().contains(&Fact::ArmEmpty));
}

#[test]
fn a_domain_file_gives_the_plan_its_action_names_and_must_be_the_problems() {
    let hyphenated = pddl::Domain::parse(
        "(define (domain BLOCKS) (:requirements :strips :typing) (:types block)
          (:predicates (on ?x - block ?y - block) (ontable ?x - block) (clear ?x - block) (handempty) (holding ?x - block))
          (:action pick-up :parameters (?x - block) :precondition (and (clear ?x) (ontable ?x) (handempty))
            :effect (and (not (ontable ?x)) (not (clear ?x)) (not (handempty)) (holding ?x)))
          (:action put-down :parameters (?x - block) :precondition (holding ?x)
            :effect (and (not (holding ?x)) (clear ?x) (handempty) (ontable ?x)))
          (:action stack :parameters (?x - block ?y - block) :precondition (and (holding ?x) (clear ?y))
            :effect (and (not (holding ?x)) (not (clear ?y)) (clear ?x) (handempty) (on ?x ?y)))
          (:action unstack :parameters (?x - block ?y - block) :precondition (and (on ?x ?y) (clear ?x) (handempty))
            :effect (and (holding ?x) (clear ?y) (not (clear ?x)) (not (handempty)) (not (on ?x ?y)))))",
    )
    .unwrap();
    let text = "(define (problem p) (:domain blocks) (:objects b1 b2 b3)
      (:init (handempty) (clear b3) (on b3 b1) (ontable b1) (clear b2) (ontable b2))
      (:goal (and (on b1 b2) (ontable b2))))";
    let problem = Problem::parse_in(text, "p.pddl", Some(&hyphenated)).unwrap();
    let plan = problem.solve(&NearOptimal::new()).unwrap();
    let printed = plan.text(&problem);
    assert!(
        printed.starts_with("(unstack b3 b1)\n(put-down b3)\n(pick-up b1)\n(stack b1 b2)\n"),
        "{printed}"
    );
    // The plan reads back, in either spelling, and replays.
    assert_eq!(problem.parse_plan(&printed).unwrap(), plan.actions);
    let plain = Problem::parse(text).unwrap();
    assert_eq!(plain.parse_plan(&printed).unwrap(), plan.actions);
    assert!(plain.plan_text(&plan.actions).contains("(putdown b3)"));
    // A problem of another domain than the file's is refused, naming both.
    let err = Problem::parse_in(
        &text.replace("(:domain blocks)", "(:domain bw)"),
        "p.pddl",
        Some(&hyphenated),
    )
    .unwrap_err()
    .to_string();
    assert_eq!(
        err,
        "p.pddl, line 1: the problem is of the domain bw, but the domain file defines BLOCKS"
    );
}

#[test]
fn a_goal_means_what_the_file_says() {
    // b2 stands on b1 and b1 on the table: the goal (on b2 b1) (on-table b1) holds. The
    // same facts without (on-table b1) are refused, not read as b1 on the table.
    let text = |goal: &str| {
        format!(
            "(define (problem g) (:domain blocksworld) (:objects b1 b2 b3)
              (:init (arm-empty) (clear b2) (on b2 b1) (on-table b1) (clear b3) (on-table b3))
              (:goal (and {goal})))"
        )
    };
    let read = Problem::parse(&text("(on b2 b1) (on-table b1)")).unwrap();
    assert!(read.goal().holds(read.start()));
    assert_eq!(read.goal().support(2), None);
    let err = Problem::parse(&text("(on b2 b1)")).unwrap_err().to_string();
    assert!(err.contains("does not say what b1 stands on"), "{err}");
    // A bottom on the table where on-table says so, and only there: b1 on b3 is another goal.
    let other = Problem::parse(&text("(on b2 b1) (on b1 b3) (on-table b3)")).unwrap();
    assert!(!other.goal().holds(other.start()));
}

#[test]
fn a_plan_that_breaks_the_rules_or_misses_the_goal_is_refused() {
    let p = Problem::parse(
        "(define (problem r) (:domain blocksworld) (:objects b1 b2)
          (:init (arm-empty) (clear b1) (clear b2) (on-table b1) (on-table b2))
          (:goal (and (on b1 b2) (on-table b2))))",
    )
    .unwrap();
    let ok = p
        .parse_plan("(pickup b1)\n(stack b1 b2)\n; cost = 2 (unit cost)\n")
        .unwrap();
    assert_eq!(ok, [Action::Pickup(0), Action::Stack(0, 1)]);
    p.replay(&ok).unwrap();
    let err = p
        .replay(&[Action::Pickup(0), Action::Pickup(1)])
        .unwrap_err()
        .to_string();
    assert_eq!(err, "plan step 2, (pickup b2): (arm-empty) does not hold");
    let err = p.replay(&[Action::Unstack(0, 1)]).unwrap_err().to_string();
    assert_eq!(err, "plan step 1, (unstack b1 b2): (on b1 b2) does not hold");
    let err = p
        .replay(&[Action::Pickup(0), Action::Putdown(0)])
        .unwrap_err()
        .to_string();
    assert_eq!(err, "after the plan's 2 steps the goal's (on b1 b2) does not hold");
    let err = p.parse_plan("(pickup b1)\n(fly b1)\n").unwrap_err().to_string();
    assert!(err.starts_with("plan line 2: (fly b1) is not an action"), "{err}");
    let err = p.parse_plan("(stack b1 b7)").unwrap_err().to_string();
    assert!(err.contains("names b7, which the problem does not declare"), "{err}");
}

#[test]
fn the_writer_keeps_the_competitions_layout() {
    let start = Towers::new(&[vec![3, 4, 2], vec![0, 1]]).unwrap();
    let goal = TowerGoal::new(&[vec![2, 3], vec![1], vec![4, 0]]).unwrap();
    let p = Problem::new("blocksworld-01", start, goal).unwrap();
    assert_eq!(
        p.to_string(),
        "(define (problem blocksworld-01)
 (:domain blocksworld)
 (:objects b1 b2 b3 b4 b5 - object)
 (:init
    (arm-empty)
    (clear b2)
    (on b2 b1)
    (on-table b1)
    (clear b3)
    (on b3 b5)
    (on b5 b4)
    (on-table b4))
 (:goal (and
    (clear b4)
    (on b4 b3)
    (on-table b3)
    (clear b2)
    (on-table b2)
    (clear b1)
    (on b1 b5)
    (on-table b5))))
"
    );
    // The start's towers by their bottom block; the goal's as given.
    assert_eq!(p.init_facts()[1], Fact::Clear(1));
    assert!(
        Problem::new(
            "two words",
            Towers::new(&[vec![0]]).unwrap(),
            TowerGoal::new(&[]).unwrap()
        )
        .is_err()
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// What is written reads back as the same problem, and the near-optimal planner's plan,
    /// printed in the competition's format and read back, replays over the file's facts to
    /// the goal, at two actions per move.
    #[test]
    fn problems_round_trip_and_plans_replay(n in 1usize..40, ipc: bool, seed: u64, named in 0usize..40) {
        let full = problem(n, ipc, seed);
        // Also goals that place only some blocks (the rest free), by dropping whole towers.
        let goal = if named % 3 == 0 {
            full.goal().clone()
        } else {
            let towers: Vec<Vec<usize>> = full.goal().towers().iter().filter(|t| t[0] % 3 != named % 3).cloned().collect();
            TowerGoal::new(&towers).unwrap()
        };
        let p = Problem::new("p", full.start().clone(), goal).unwrap();
        let text = p.to_string();
        let back = Problem::parse(&text).unwrap();
        prop_assert_eq!(&back, &p);
        prop_assert_eq!(back.to_string(), text);
        let plan = NearOptimal::new().plan(p.start(), p.goal()).unwrap();
        let actions = pddl::actions(p.start(), &plan).unwrap();
        prop_assert_eq!(actions.len(), 2 * plan.len());
        let printed = p.plan_text(&actions);
        let read = back.parse_plan(&printed).unwrap();
        prop_assert_eq!(&read, &actions);
        back.replay(&read).unwrap();
    }

    /// On small problems the exact solver's plans replay too, and are never longer.
    #[test]
    fn exact_plans_replay(n in 1usize..8, ipc: bool, seed: u64) {
        let p = problem(n, ipc, seed);
        let exact = ExactMoves::new().solve(p.start(), p.goal()).unwrap();
        let near = NearOptimal::new().plan(p.start(), p.goal()).unwrap();
        prop_assert!(exact.len() <= near.len() && near.len() <= 2 * exact.len());
        p.replay(&pddl::actions(p.start(), &exact).unwrap()).unwrap();
    }

    /// Any text gives a problem or an error, never a panic; what parses prints back to
    /// itself.
    #[test]
    fn any_text_is_read_or_refused(text in "[()a-z0-9 :;\n-]{0,200}") {
        if let Ok(p) = Problem::parse(&text) {
            prop_assert_eq!(Problem::parse(&p.to_string()).unwrap(), p);
        }
    }
}

#[test]
fn random_goals_of_few_towers_round_trip() {
    for seed in 0..20 {
        let start = random_state(12, seed);
        let goal = random_goal(12, 1 + seed as usize % 3, 7, seed).unwrap();
        let p = Problem::new("g", start, goal).unwrap();
        assert_eq!(Problem::parse(&p.to_string()).unwrap(), p);
    }
}

#[test]
fn the_competition_shape_has_few_tall_towers() {
    // Each block after the first starts a tower with probability 1/10.
    let towers: usize = (0..200).map(|s| ipc_state(100, s).tower_count()).sum();
    let mean = towers as f64 / 200.0;
    assert!((9.0..12.8).contains(&mean), "{mean}");
    assert_eq!(ipc_state(30, 5), ipc_state(30, 5));
}
