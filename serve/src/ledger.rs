//! What a study's record folder keeps beside the recordings, so that a restarted server
//! still knows it: a secret key, which session token reaches which recording, and the
//! withdrawn participants' ids when their recordings were deleted.
//!
//! Nothing here is kept in the clear. Tokens and ids are stored as keyed hashes
//! (HMAC-SHA-256 under the folder's own key), so the file gives no one a way into a
//! session, and after `withdrawal = "delete"` nothing of a participant is left but the
//! hash that stops the same id from joining again. The same key derives each participant's
//! own completion code (`code_per_participant`), so the code needs no storing either.
//!
//! The file is `DIR/.serve-ledger.jsonl` (a dot file: a glob of recordings leaves it out),
//! JSON Lines, one write and one flush per line like a recording:
//!
//! ```text
//! {"type":"ledger","format":"blockstack-serve-ledger","version":1,"key":"<64 hex digits>"}
//! {"type":"session","token":"<hash>","recording":"p0003-top.jsonl"}
//! {"type":"withdrawn","id":"<hash>"}
//! ```
//!
//! It is made with the first participant who acts, readable by its owner only. Without a
//! study the key lives in memory for the run.

use std::collections::{HashMap, HashSet};
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// The ledger's file name in a record folder.
pub(crate) const LEDGER_FILE: &str = ".serve-ledger.jsonl";
const FORMAT: &str = "blockstack-serve-ledger";
const VERSION: u32 = 1;
/// The longest ledger read (a line is under 200 bytes: some five million lines).
const MAX_LEDGER_BYTES: u64 = 1 << 30;

/// One line of the ledger.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
enum Line {
    /// The header: the folder's key.
    Ledger { format: String, version: u32, key: String },
    /// A session token (hashed) and the recording it reaches.
    Session { token: String, recording: String },
    /// A withdrawn participant's platform id (hashed), their recording deleted.
    Withdrawn { id: String },
}

/// The record folder's ledger (module docs).
pub(crate) struct Ledger {
    key: [u8; 32],
    path: Option<PathBuf>,
    sessions: HashMap<String, String>,
    withdrawn: HashSet<String>,
}

impl Ledger {
    /// The ledger of the record folder `dir` (made with a fresh key when it has none), or
    /// one in memory without a folder.
    pub(crate) fn open(dir: Option<&Path>) -> Result<Ledger, String> {
        let mut ledger = Ledger {
            key: fresh_key(),
            path: dir.map(|d| d.join(LEDGER_FILE)),
            sessions: HashMap::new(),
            withdrawn: HashSet::new(),
        };
        let Some(path) = ledger.path.clone() else {
            return Ok(ledger);
        };
        if std::fs::symlink_metadata(&path).is_err() {
            return Ok(ledger);
        }
        let bad = |why: String| format!("{}: {why}", path.display());
        let mut text = String::new();
        std::io::Read::read_to_string(
            &mut files::open_bounded(&path, MAX_LEDGER_BYTES, "a study's ledger").map_err(|e| e.to_string())?,
            &mut text,
        )
        .map_err(|e| bad(format!("cannot read: {e}")))?;
        for (n, raw) in text.lines().enumerate() {
            // A line a kill cut short is the last one, and not needed: its session has its
            // token in the page, and is let go on the next restart.
            let Ok(line) = serde_json::from_str::<Line>(raw) else {
                continue;
            };
            match line {
                Line::Ledger { format, version, key } if n == 0 => {
                    if format != FORMAT || version != VERSION {
                        return Err(bad(format!(
                            "it is {format} version {version}, not {FORMAT} version {VERSION}"
                        )));
                    }
                    ledger.key = parse_key(&key).ok_or_else(|| bad("its key is not 64 hex digits".into()))?;
                }
                Line::Ledger { .. } => return Err(bad(format!("line {}: a second header", n + 1))),
                _ if n == 0 => return Err(bad("it does not begin with its header line".into())),
                Line::Session { token, recording } => {
                    ledger.sessions.insert(token, recording);
                }
                Line::Withdrawn { id } => {
                    ledger.withdrawn.insert(id);
                }
            }
        }
        Ok(ledger)
    }

    /// The keyed hash of `text` for the purpose `what` (a token, an id, a code).
    fn hash(&self, what: &str, text: &str) -> String {
        hex(&hmac(&self.key, format!("{what}\0{text}").as_bytes()))
    }

    /// The recording the session token `token` reaches, if the ledger knows it.
    pub(crate) fn recording_of(&self, token: &str) -> Option<&str> {
        self.sessions.get(&self.hash("token", token)).map(String::as_str)
    }

    /// Remembers that `token` reaches the recording `file`.
    pub(crate) fn remember(&mut self, token: &str, file: &str) -> Result<(), String> {
        let line = Line::Session {
            token: self.hash("token", token),
            recording: file.to_string(),
        };
        if let Line::Session { token, recording } = &line {
            self.sessions.insert(token.clone(), recording.clone());
        }
        self.append(&line)
    }

    /// Whether a participant with the platform id `id` withdrew and had their recording
    /// deleted.
    pub(crate) fn withdrew(&self, id: &str) -> bool {
        self.withdrawn.contains(&self.hash("id", id))
    }

    /// A participant whose recording `file` was deleted on withdrawal: their tokens are
    /// forgotten, and only the hash of their platform id `id` (when they had one) is kept.
    pub(crate) fn withdraw_deleted(&mut self, file: &str, id: Option<&str>) -> Result<(), String> {
        self.sessions.retain(|_, f| f != file);
        if let Some(id) = id {
            self.withdrawn.insert(self.hash("id", id));
        }
        self.rewrite()
    }

    /// The completion codes of a study whose own code is `shared`, or whose participants
    /// each have theirs (`per_participant`), derived from this ledger's key.
    pub(crate) fn codes(&self, shared: Option<&str>, per_participant: bool) -> Codes {
        match (per_participant, shared) {
            (true, _) => Codes::Own(self.key),
            (false, Some(code)) => Codes::Shared(code.to_string()),
            (false, None) => Codes::None,
        }
    }

    /// Appends `line`, made part of the ledger already (the whole ledger is written when
    /// its file does not exist yet).
    fn append(&self, line: &Line) -> Result<(), String> {
        let Some(path) = &self.path else {
            return Ok(());
        };
        if std::fs::symlink_metadata(path).is_err() {
            return self.rewrite();
        }
        let mut text = serde_json::to_string(line).expect("ledger lines serialise");
        text.push('\n');
        let out = files::OutputPath::check(path).map_err(|e| e.to_string())?;
        let mut file = out.append().map_err(|e| e.to_string())?;
        file.write_all(text.as_bytes())
            .and_then(|()| file.flush())
            .map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Writes the whole ledger again (atomically), readable by its owner only.
    fn rewrite(&self) -> Result<(), String> {
        let Some(path) = &self.path else {
            return Ok(());
        };
        let mut lines = vec![Line::Ledger {
            format: FORMAT.into(),
            version: VERSION,
            key: hex(&self.key),
        }];
        let mut sessions: Vec<_> = self.sessions.iter().collect();
        sessions.sort();
        lines.extend(sessions.into_iter().map(|(t, r)| Line::Session {
            token: t.clone(),
            recording: r.clone(),
        }));
        let mut withdrawn: Vec<_> = self.withdrawn.iter().collect();
        withdrawn.sort();
        lines.extend(withdrawn.into_iter().map(|id| Line::Withdrawn { id: id.clone() }));
        let text: String = lines
            .iter()
            .map(|l| serde_json::to_string(l).expect("ledger lines serialise") + "\n")
            .collect();
        files::write(path, text.as_bytes()).map_err(|e| e.to_string())?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o600))
                .map_err(|e| format!("{}: {e}", path.display()))?;
        }
        Ok(())
    }
}

/// A study's completion codes: none, the study's one code, or each participant's own.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) enum Codes {
    /// The study gives none.
    #[default]
    None,
    /// Every participant gets the study's code.
    Shared(String),
    /// Each participant gets a code of their own, derived from the ledger's key.
    Own([u8; 32]),
}

impl Codes {
    /// Participant `number`'s code: with [`Codes::Own`] eight letters and digits, the same
    /// on every run of the folder, unguessable without its key.
    pub(crate) fn of(&self, number: u64) -> Option<String> {
        // Letters and digits that cannot be misread for one another (no 0/O, 1/I/L).
        const ALPHABET: &[u8] = b"ABCDEFGHJKMNPQRSTUVWXYZ23456789";
        match self {
            Codes::None => None,
            Codes::Shared(code) => Some(code.clone()),
            Codes::Own(key) => Some(
                hmac(key, format!("code\0{number}").as_bytes())
                    .iter()
                    .take(8)
                    .map(|b| char::from(ALPHABET[usize::from(*b) % ALPHABET.len()]))
                    .collect(),
            ),
        }
    }
}

fn fresh_key() -> [u8; 32] {
    use rand::RngExt;
    rand::rng().random()
}

fn parse_key(text: &str) -> Option<[u8; 32]> {
    if text.len() != 64 {
        return None;
    }
    let mut key = [0u8; 32];
    for (i, byte) in key.iter_mut().enumerate() {
        *byte = u8::from_str_radix(text.get(2 * i..2 * i + 2)?, 16).ok()?;
    }
    Some(key)
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// HMAC-SHA-256 (RFC 2104) of `message` under `key` (32 bytes, under SHA-256's block):
/// written here over `sha2`, the workspace's hash, rather than a crate for twelve lines.
fn hmac(key: &[u8; 32], message: &[u8]) -> [u8; 32] {
    let mut block = [0u8; 64];
    block[..32].copy_from_slice(key);
    let pad = |byte: u8| block.map(|k| k ^ byte);
    let inner = Sha256::new().chain_update(pad(0x36)).chain_update(message).finalize();
    Sha256::new()
        .chain_update(pad(0x5c))
        .chain_update(inner)
        .finalize()
        .into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hmac_matches_rfc_4231() {
        // RFC 4231 test case 2's message under a key padded to our 32 bytes would differ; case
        // 1's key is 20 bytes of 0x0b: the same HMAC as that key zero-padded to 32.
        let mut key = [0u8; 32];
        key[..20].fill(0x0b);
        assert_eq!(
            hex(&hmac(&key, b"Hi There")),
            "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7"
        );
    }

    #[test]
    fn a_ledger_keeps_hashes_only_and_survives_a_restart() {
        let dir = tempfile::tempdir().unwrap();
        let mut ledger = Ledger::open(Some(dir.path())).unwrap();
        ledger.remember("tok1", "p0000-a.jsonl").unwrap();
        ledger.remember("tok2", "p0001-a.jsonl").unwrap();
        ledger.withdraw_deleted("p0001-a.jsonl", Some("PID-2")).unwrap();
        let code = ledger.codes(None, true).of(7).unwrap();
        let text = std::fs::read_to_string(dir.path().join(LEDGER_FILE)).unwrap();
        for secret in ["tok1", "tok2", "PID-2", "p0001"] {
            assert!(!text.contains(secret), "{secret} in {text}");
        }
        let again = Ledger::open(Some(dir.path())).unwrap();
        assert_eq!(again.recording_of("tok1"), Some("p0000-a.jsonl"));
        assert_eq!(again.recording_of("tok2"), None);
        assert!(again.withdrew("PID-2") && !again.withdrew("PID-3"));
        let codes = again.codes(None, true);
        assert_eq!(codes.of(7), Some(code.clone()));
        assert_ne!(codes.of(8), Some(code.clone()));
        assert_eq!(code.len(), 8);
        assert_eq!(again.codes(Some("C0DE"), false).of(8).as_deref(), Some("C0DE"));
        // Another folder, another key: another code.
        let other = tempfile::tempdir().unwrap();
        assert_ne!(
            Ledger::open(Some(other.path())).unwrap().codes(None, true).of(7),
            Some(code)
        );
    }
}
