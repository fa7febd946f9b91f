//! A server restarted on the same record folder goes on from what the folder holds:
//! participant numbers, the study's cap and the balance of its conditions.

use crate::common::*;
use serve::ServeConfig;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn numbering_the_cap_and_the_balance_go_on_after_a_restart() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study.toml");
    std::fs::write(
        &study,
        "name = \"pilot\"\nmax_participants = 4\n\n[[condition]]\nname = \"a\"\n\n[[condition]]\nname = \"a-b\"\n\n[[condition]]\nname = \"c\"\n",
    )
    .unwrap();
    let record = dir.path().join("out");
    let config = || ServeConfig {
        study: Some(study.clone()),
        record_dir: Some(record.clone()),
        ..ServeConfig::default()
    };
    let (first, _) = start(config()).await;
    join(first, "x").await.unwrap();
    join(first, "y").await.unwrap();
    // A second run on the same folder (the first could have been killed: nothing it held
    // in memory is needed).
    let (second, _) = start(config()).await;
    join(second, "z").await.unwrap();
    let mut names: Vec<String> = std::fs::read_dir(&record)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    // Numbers go on (never two p0000), and the condition no one has yet comes next.
    assert_eq!(names, ["p0000-a-x.jsonl", "p0001-a-b-y.jsonl", "p0002-c-z.jsonl"]);
    for (name, condition) in [("p0001-a-b-y.jsonl", "a-b"), ("p0002-c-z.jsonl", "c")] {
        let header = &lines(&record.join(name))[0];
        assert_eq!(header["participant"]["condition"], condition);
    }
    // The cap of 4 counts the first run's participants: one more, then no one.
    join(second, "w").await.unwrap();
    let (status, body) = join(second, "v").await.unwrap_err();
    assert_eq!(status, 503, "{body}");
    assert!(body.contains("takes 4 participants"), "{body}");
    let (third, _) = start(config()).await;
    assert_eq!(join(third, "u").await.unwrap_err().0, 503);
}
