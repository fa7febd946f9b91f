//! `train --preset`: the role representation trains with the role recipe by default, the
//! paper's representations with the paper's learner, and every flag overrides its preset.

use crate::common::{cli, model_metadata, path, scratch, stderr, stdout, train, train_model};

#[test]
fn the_role_learner_with_its_default_preset_plays_every_goal_greedily() {
    let dir = scratch("preset-role");
    let run = [
        "--repr",
        "role",
        "--reward",
        "step-cost",
        "--goals",
        "0,1,2",
        "--games",
        "20000",
    ];
    let model = train_model(&dir, "role.st", &run);
    let training = &model_metadata(&model)["training"];
    assert_eq!(training["params"]["gamma"], 1.0, "{training}");
    assert_eq!(training["final_replay"], true, "{training}");
    let report: serde_json::Value = cli("eval")
        .flag("model", path(&model))
        .flag("episodes", "100")
        .flag("epsilon", "0")
        .arg("--json")
        .json();
    assert_eq!(report["episodes"], 600, "{report}");
    assert_eq!(report["failures"], 0, "{report}");
}

#[test]
fn presets_set_the_learner_and_flags_override_them() {
    let dir = scratch("preset-flags");
    let model = dir.join("m.st");
    let trained = |args: &[&str]| {
        let run = [
            "--goals",
            "0,1,2",
            "--games",
            "5",
            "--backend",
            "grid",
            "--out",
            path(&model),
        ];
        train(&[&run[..], args].concat());
        model_metadata(&model)["training"].clone()
    };
    // The paper's representation: the paper's learner.
    let t = trained(&[]);
    assert_eq!(
        (t["repr"].as_str(), t["params"]["gamma"].as_f64(), &t["final_replay"]),
        (Some("chasing"), Some(0.1), &false.into())
    );
    // --preset optimal is the role recipe.
    let t = trained(&["--preset", "optimal"]);
    assert_eq!(
        (t["repr"].as_str(), t["reward"]["model"].as_str()),
        (Some("role"), Some("step-cost")),
        "{t}"
    );
    assert_eq!(
        (t["params"]["epsilon"].as_f64(), &t["backward_replay"]),
        (Some(0.0), &true.into()),
        "{t}"
    );
    // Explicit flags beat the preset.
    let t = trained(&["--repr", "role", "--epsilon", "0.2", "--final-replay=false"]);
    assert_eq!(
        (
            t["params"]["epsilon"].as_f64(),
            &t["final_replay"],
            &t["backward_replay"]
        ),
        (Some(0.2), &false.into(), &true.into()),
        "{t}"
    );
    let t = trained(&["--repr", "role", "--preset", "paper"]);
    assert_eq!(
        (t["repr"].as_str(), t["params"]["gamma"].as_f64(), &t["backward_replay"]),
        (Some("role"), Some(0.1), &false.into()),
        "{t}"
    );
    // The original profile's learner is the paper's as coded; the role recipe's replays
    // need the spec schedule.
    let t = trained(&["--profile", "original", "--repr", "role"]);
    assert_eq!(
        (t["schedule"].as_str(), t["params"]["gamma"].as_f64()),
        (Some("paper-code"), Some(0.1)),
        "{t}"
    );
    let t = trained(&["--profile", "original", "--preset", "optimal", "--schedule", "spec"]);
    assert_eq!(
        (t["repr"].as_str(), &t["final_replay"]),
        (Some("role"), &true.into()),
        "{t}"
    );
    let o = cli("train")
        .flag("profile", "original")
        .flag("preset", "optimal")
        .flag("out", path(&model))
        .run();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("add --schedule spec"), "{}", stderr(&o));

    let help = stdout(&cli("train").arg("--help").run());
    assert!(
        help.contains("--preset") && help.contains("optimal") && help.contains("an explicit flag beats both"),
        "{help}"
    );
}
