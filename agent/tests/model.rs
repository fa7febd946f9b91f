//! Model files (format 2, safetensors): round trips bit for bit in every layout and value
//! type, and a clear refusal of every bad file.

use std::path::Path;

use crate::common::{TempPath, temp_path};

use agent::model::{MAX_MODEL_BYTES, MODEL_FORMAT, MODEL_VERSION};
use agent::{CorrectionRule, QAgent, QParams, QTable, ReprKind, TrainConfig};
use files::{Container, Dtype, Expect, Tensor};
use serde_json::{Value, json};
use sim::{Backend, Goal, Grid};

fn goal(text: &str) -> Goal {
    text.parse().unwrap()
}

/// Our role + step-cost learner, on the grid backend (quick enough for tests).
fn role_config(goals: &[&str], games: u64, seed: u64) -> TrainConfig {
    TrainConfig {
        games,
        seed,
        ..TrainConfig::role_step_cost(goals.iter().map(|g| goal(g)).collect())
    }
    .with_backend(Backend::Grid)
}

/// Every value of two tables, bit for bit (`QTable`'s `==` says `-0.0 == 0.0`).
fn assert_same_bits(a: &QTable, b: &QTable) {
    assert_eq!((a.key_count(), a.columns()), (b.key_count(), b.columns()));
    assert_eq!(a.initial().to_bits(), b.initial().to_bits());
    let bits = |t: &QTable| -> Vec<(u64, Vec<u32>)> {
        t.written_rows()
            .into_iter()
            .map(|(k, row)| (k, row.iter().map(|v| v.to_bits()).collect()))
            .collect()
    };
    assert_eq!(bits(a), bits(b));
}

/// Saves and loads `agent`; checks the load gives back the same agent bit for bit, and
/// returns the file's `values` dtype and whether it stored keys (the rows layout).
fn round_trip(agent: &QAgent, name: &str) -> (Dtype, bool) {
    let path = temp_path(name);
    agent.save(&path).unwrap();
    let loaded = QAgent::load(&path).unwrap();
    assert_eq!(loaded, *agent);
    assert_same_bits(loaded.table(), agent.table());
    assert_eq!(loaded.table().is_dense(), agent.table().is_dense());
    assert_eq!(loaded.training(), agent.training());
    assert_eq!(loaded.params(), agent.params());
    let c = Container::read(
        &path,
        &Expect {
            format: MODEL_FORMAT,
            version: MODEL_VERSION,
            max_bytes: MAX_MODEL_BYTES,
            what: "a model file",
        },
    )
    .unwrap();
    (c.tensor("values").unwrap().dtype(), c.tensor("keys").is_some())
}

#[test]
fn trained_agents_round_trip_bit_for_bit() {
    // Dense (role, 3 blocks) and hashed (role, 4 blocks) tables.
    for (goals, games) in [(vec!["2,0,1"], 3000), (vec!["3,1,0,2"], 300)] {
        let trained = agent::train(&role_config(&goals, games, 7), None).unwrap();
        assert_eq!(trained.agent.table().is_dense(), goals[0].len() == 5);
        // A step-cost learner's values are small integers: one byte each.
        assert_eq!(
            round_trip(&trained.agent, &format!("{}.safetensors", goals[0])).0,
            Dtype::I8
        );
    }
    // The paper's learner: values that are not short decimals survive exactly.
    let config = TrainConfig {
        games: 200,
        ..TrainConfig::paper(vec![goal("0,1,2")])
    }
    .with_backend(Backend::Grid);
    let paper = agent::train(&config, None).unwrap().agent;
    assert_eq!(round_trip(&paper, "paper.safetensors").0, Dtype::F32);
}

/// An agent whose written rows are `rows` (key, value for every column).
fn agent_with(kind: ReprKind, blocks: usize, initial_q: f64, rows: &[(u64, f32)]) -> QAgent {
    let params = QParams {
        initial_q,
        ..QParams::default()
    };
    let mut q = QAgent::new(kind, Grid::default(), blocks, params).unwrap();
    for &(key, v) in rows {
        q.table_mut().row_mut(key).fill(v);
    }
    q
}

#[test]
fn every_value_type_and_layout_round_trips_bit_for_bit() {
    let cases: [(&[f32], Dtype); 6] = [
        (&[-1.0, 0.0, 127.0, -128.0], Dtype::I8),
        (&[300.0, -32768.0], Dtype::I16),
        (&[0.5, 1000.5], Dtype::F16),
        // -0.0 is no integer: the narrowest exact type is F16.
        (&[-0.0, 3.0], Dtype::F16),
        (&[0.1], Dtype::F32),
        (&[1e-30, 3e38, -7.25], Dtype::F32),
    ];
    for (values, dtype) in cases {
        let rows =
            |n: u64| -> Vec<(u64, f32)> { (0..n).map(|i| (i * 7 + 3, values[i as usize % values.len()])).collect() };
        // Few rows of a dense table: stored as keys + rows.
        let few = agent_with(ReprKind::Chasing, 3, 0.0, &rows(values.len() as u64));
        assert!(few.table().is_dense());
        assert_eq!(round_trip(&few, "few.safetensors"), (dtype, true), "{values:?}");
        // Every row written: the dense layout is smaller.
        let keys = few.table().key_count();
        let all: Vec<(u64, f32)> = (0..keys).map(|k| (k, values[k as usize % values.len()])).collect();
        let full = agent_with(ReprKind::Chasing, 3, 0.0, &all);
        assert_eq!(round_trip(&full, "full.safetensors"), (dtype, false), "{values:?}");
        // A hashed table (too many keys for an array).
        let hashed = agent_with(ReprKind::Role, 5, 0.0, &rows(values.len() as u64));
        assert!(!hashed.table().is_dense());
        assert_eq!(round_trip(&hashed, "hashed.safetensors"), (dtype, true), "{values:?}");
    }
    // The initial value counts too: 0.25 needs F16 even where every written value is an
    // integer.
    let q = agent_with(ReprKind::Chasing, 3, 0.25, &[(5, 1.0)]);
    assert_eq!(round_trip(&q, "initial.safetensors").0, Dtype::F16);
}

#[test]
fn values_beyond_the_tables_floats_are_refused_up_front() {
    // train --initial-q 1e300: refused by the config, before training.
    let config = TrainConfig {
        params: QParams {
            initial_q: 1e300,
            ..QParams::default()
        },
        ..TrainConfig::paper(vec![goal("0,1,2")])
    };
    let err = config.validate().unwrap_err().to_string();
    assert!(err.contains("1e300") && err.contains("32-bit floats"), "{err}");
    assert!(agent::Trainer::new(config).is_err());
    for bad in [f64::INFINITY, f64::NAN, -4e38] {
        let params = QParams {
            initial_q: bad,
            ..QParams::default()
        };
        assert!(params.validate().is_err(), "{bad}");
    }
    assert!(
        QParams {
            initial_q: -3e38,
            ..QParams::default()
        }
        .validate()
        .is_ok()
    );
    // correct --margin 1e39.
    let rule = CorrectionRule {
        margin: Some(1e39),
        ..CorrectionRule::default()
    };
    assert!(rule.validate().unwrap_err().to_string().contains("32-bit floats"));
    // A table that diverged anyway is not saved (and nothing is written).
    let q = agent_with(ReprKind::Chasing, 3, 0.0, &[(4, f32::INFINITY)]);
    let path = temp_path("diverged.safetensors");
    let err = q.save(&path).unwrap_err().to_string();
    assert!(
        err.contains("inf (key 4, column 0)") && err.contains("not a finite number"),
        "{err}"
    );
    assert!(!path.exists());
}

/// A model file made by hand: `meta` as the metadata and `tensors`, with a valid
/// checksum, so that only the model's own checks can refuse it.
fn crafted(name: &str, meta: &Value, tensors: &[(&str, Tensor<'_>)]) -> TempPath {
    let path = temp_path(name);
    let bytes = files::container::to_bytes(MODEL_FORMAT, MODEL_VERSION, meta, tensors).unwrap();
    std::fs::write(&path, bytes).unwrap();
    path
}

/// The error loading `path`, checked to name the file.
fn refusal(path: &Path) -> String {
    let message = QAgent::load(path).expect_err("the file is refused").to_string();
    assert!(message.contains(&path.display().to_string()), "{message}");
    message
}

/// A saved model's bytes.
fn saved() -> Vec<u8> {
    let trained = agent::train(&role_config(&["0,1,2"], 200, 2), None).unwrap();
    let path = temp_path("model.safetensors");
    trained.agent.save(&path).unwrap();
    std::fs::read(&path).unwrap()
}

fn written(name: &str, bytes: &[u8]) -> TempPath {
    let path = temp_path(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn damaged_and_foreign_files_are_refused_saying_which() {
    let bytes = saved();
    let load = |name: &str, b: &[u8]| refusal(&written(name, b));
    assert!(load("truncated.safetensors", &bytes[..bytes.len() / 2]).contains("truncated"));
    assert!(load("cut-header.safetensors", &bytes[..20]).contains("truncated"));
    assert!(load("empty.safetensors", &[]).contains("truncated"));
    assert!(load("garbage.safetensors", b"\x01\x02not a model").contains("not a safetensors file"));
    let mut flipped = bytes.clone();
    let last = flipped.len() - 1;
    flipped[last] ^= 1;
    assert!(load("flipped.safetensors", &flipped).contains("checksum"));
    // Another version: the header's version string, patched in place.
    let header_end = 8 + u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let at = bytes[..header_end]
        .windows(13)
        .position(|w| w == b"\"version\":\"2\"")
        .expect("the version in the header");
    let mut newer = bytes.clone();
    newer[at + 11] = b'3';
    let err = load("newer.safetensors", &newer);
    assert!(err.contains("version 3") && err.contains("newer"), "{err}");
    // Another format, and a safetensors file of no format.
    let other = files::container::to_bytes("another-format", 2, &json!({}), &[]).unwrap();
    assert!(load("other.safetensors", &other).contains("another-format"));
    // The safetensors layout by hand: header length, JSON header, one byte of data.
    let header = br#"{"values":{"dtype":"U8","shape":[1],"data_offsets":[0,1]}}"#;
    let mut plain = (header.len() as u64).to_le_bytes().to_vec();
    plain.extend_from_slice(header);
    plain.push(1);
    assert!(load("plain.safetensors", &plain).contains("not blockstack-q-agent"));
    // A missing file, a directory, and devices.
    let missing = temp_path("no-such-model.safetensors");
    assert!(
        QAgent::load(&missing)
            .unwrap_err()
            .to_string()
            .contains("no-such-model.safetensors")
    );
    assert!(
        QAgent::load(missing.parent().unwrap())
            .unwrap_err()
            .to_string()
            .contains("directory")
    );
    let zero = QAgent::load(Path::new("/dev/zero")).unwrap_err().to_string();
    assert!(
        zero.contains("/dev/zero") && zero.contains("a pipe or a device"),
        "{zero}"
    );
    // A file larger than any model, refused by its size without a byte read (a sparse
    // file: no disk is used).
    let huge = temp_path("huge.safetensors");
    std::fs::File::create(&huge)
        .unwrap()
        .set_len(MAX_MODEL_BYTES + 1)
        .unwrap();
    assert!(refusal(&huge).contains("larger than 1 GiB, the most a model file can be"));
    std::fs::remove_file(&huge).unwrap();
}

#[test]
fn a_version_1_json_model_is_named_as_such() {
    let v1 = r#"{"format":"blockstack-q-agent","version":1,"grid":{"width":7,"height":7},"blocks":3,"repr":"role","params":{"alpha":1.0,"gamma":0.1,"epsilon":0.1,"initial_q":0.0},"training":null,"table":{"keys":470596,"columns":8,"initial":0.0,"rows":[],"checksum":0}}"#;
    let err = refusal(&written("v1.json", v1.as_bytes()));
    assert!(
        err.contains("version-1 model file (JSON)") && err.contains("train the model again"),
        "{err}"
    );
    // Other JSON is not a model of any version.
    assert!(refusal(&written("other.json", br#"{"hello": 1}"#)).contains("not a safetensors file"));
}

/// The metadata of an untrained 3-block role agent, as the file holds it.
fn role_meta() -> Value {
    json!({
        "grid": {"width": 7, "height": 7}, "blocks": 3, "repr": "role",
        "params": {"alpha": 1.0, "gamma": 0.1, "epsilon": 0.1, "initial_q": 0.0},
        "training": null,
        "table": {"keys": 470596, "columns": 8, "initial": 0.0}
    })
}

fn no_rows() -> Vec<(&'static str, Tensor<'static>)> {
    vec![
        ("keys", Tensor::from_values::<u32>(&[0], &[]).unwrap()),
        ("values", Tensor::from_values::<i8>(&[0, 8], &[]).unwrap()),
    ]
}

#[test]
fn tables_that_do_not_fit_their_model_are_refused() {
    assert!(QAgent::load(&crafted("fine.safetensors", &role_meta(), &no_rows())).is_ok());
    let with = |name: &str, change: &dyn Fn(&mut Value), tensors: &[(&str, Tensor<'_>)]| {
        let mut meta = role_meta();
        change(&mut meta);
        refusal(&crafted(name, &meta, tensors))
    };
    // Shapes are checked against the representation before anything is allocated.
    let err = with("reshaped.safetensors", &|m| m["repr"] = json!("chasing"), &no_rows());
    assert!(err.contains("but a chasing table for 3 blocks"), "{err}");
    let err = with(
        "huge.safetensors",
        &|m| m["table"]["columns"] = json!(1_000_000_000_000u64),
        &no_rows(),
    );
    assert!(err.contains("1000000000000 columns"), "{err}");
    let err = with("blocks.safetensors", &|m| m["blocks"] = json!(40), &no_rows());
    assert!(err.contains("40 blocks is not allowed"), "{err}");
    assert!(with("unknown.safetensors", &|m| m["extra"] = json!(1), &no_rows()).contains("metadata does not parse"));
    // Tensors that contradict the metadata.
    let rows = |keys: &[u32], values: Tensor<'static>| {
        vec![
            ("keys", Tensor::from_values(&[keys.len()], keys).unwrap()),
            ("values", values),
        ]
    };
    let ones = |n: usize| Tensor::from_values(&[n, 8], &vec![1i8; n * 8]).unwrap();
    assert!(
        with(
            "no-values.safetensors",
            &|_| {},
            &[("keys", Tensor::from_values::<u32>(&[0], &[]).unwrap())]
        )
        .contains("no \"values\"")
    );
    assert!(with("order.safetensors", &|_| {}, &rows(&[5, 3], ones(2))).contains("in key order"));
    assert!(with("range.safetensors", &|_| {}, &rows(&[470596], ones(1))).contains("in key order"));
    assert!(with("count.safetensors", &|_| {}, &rows(&[1, 2, 3], ones(2))).contains("shape"));
    let columns = Tensor::from_values(&[1, 7], &[1i8; 7]).unwrap();
    assert!(with("columns.safetensors", &|_| {}, &rows(&[1], columns)).contains("7 columns"));
    let bytes = Tensor::from_values(&[1, 8], &[1u8; 8]).unwrap();
    assert!(with("dtype.safetensors", &|_| {}, &rows(&[1], bytes)).contains("not one of I8, I16, F16, F32"));
    let nan = Tensor::from_values(&[1, 8], &[f32::NAN; 8]).unwrap();
    assert!(with("nan.safetensors", &|_| {}, &rows(&[1], nan)).contains("not a finite number"));
    let dense = vec![("values", ones(3))];
    assert!(with("dense.safetensors", &|_| {}, &dense).contains("a dense \"values\" has 3 rows"));
    assert!(
        with(
            "initial.safetensors",
            &|m| m["table"]["initial"] = json!(0.1),
            &no_rows()
        )
        .contains("not a 32-bit float")
    );
}

#[test]
fn a_training_config_that_contradicts_the_model_is_refused() {
    let training = serde_json::to_value(agent::model::TrainingMeta::of(&TrainConfig::role_step_cost(vec![
        goal("0,1,2"),
    ])))
    .unwrap();
    let with = |name: &str, change: &dyn Fn(&mut Value)| {
        let mut meta = role_meta();
        meta["training"] = training.clone();
        change(&mut meta["training"]);
        crafted(name, &meta, &no_rows())
    };
    assert!(QAgent::load(&with("trained.safetensors", &|_| {})).is_ok());
    let err = refusal(&with("repr.safetensors", &|t| t["repr"] = json!("chasing")));
    assert!(err.contains("inconsistent"), "{err}");
    let err = refusal(&with("no-goals.safetensors", &|t| t["goals"] = json!([])));
    assert!(err.contains("lists no goals"), "{err}");
    let err = refusal(&with("goal-blocks.safetensors", &|t| {
        t["goals"] = json!([[0, 1, 2], [1, 0]])
    }));
    assert!(err.contains("training goal 1,0 has 2 blocks"), "{err}");
}

#[test]
fn seen_entries_belong_to_paper_code_models_and_must_fit() {
    let mut meta = role_meta();
    meta["schedule"] = json!("paper-code");
    let seen = |keys: &[u32], bits: &[u32]| {
        let mut t = no_rows();
        t.push(("seen_keys", Tensor::from_values(&[keys.len()], keys).unwrap()));
        t.push(("seen", Tensor::from_values(&[bits.len()], bits).unwrap()));
        t
    };
    let agent = QAgent::load(&crafted("seen.safetensors", &meta, &seen(&[3, 9], &[0b1, 0b1010_0000]))).unwrap();
    assert_eq!(agent.schedule(), agent::Schedule::PaperCode);
    assert_eq!(agent.table().seen_entries(), vec![(3, 1), (9, 0b1010_0000)]);
    let err = refusal(&crafted("unseen.safetensors", &meta, &no_rows()));
    assert!(err.contains("lacks its seen entries"), "{err}");
    let err = refusal(&crafted("spec-seen.safetensors", &role_meta(), &seen(&[3], &[1])));
    assert!(err.contains("spec schedule has seen entries"), "{err}");
    let err = refusal(&crafted("bits.safetensors", &meta, &seen(&[3], &[1 << 8])));
    assert!(err.contains("does not fit a table"), "{err}");
    let err = refusal(&crafted("seen-order.safetensors", &meta, &seen(&[9, 3], &[1, 1])));
    assert!(err.contains("in key order"), "{err}");
    // The training config names the schedule the agent learns by.
    meta["training"] = serde_json::to_value(agent::model::TrainingMeta::of(&TrainConfig::role_step_cost(vec![
        goal("0,1,2"),
    ])))
    .unwrap();
    let err = refusal(&crafted("schedule.safetensors", &meta, &seen(&[3], &[1])));
    assert!(err.contains("learns by the paper-code schedule"), "{err}");
}
