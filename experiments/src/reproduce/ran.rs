//! Where a run happened: the commit, the machine and the threads, so that a report's
//! figures and timings can be traced (the figures do not depend on the machine or the
//! threads; the time a run takes does).

use serde::Serialize;

/// Where a reproduction ran, written into `results.json` and at the top of the report.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Ran {
    /// The commit of the source the program was built from (`git rev-parse --short HEAD`
    /// in it), or "unknown" without git or without the source.
    pub commit: String,
    /// The CPU's model name (from `/proc/cpuinfo`), or "unknown".
    pub cpu: String,
    /// Logical cores available to the program.
    pub cores: usize,
    /// Threads the experiments ran on (`--jobs`).
    pub threads: usize,
}

impl Ran {
    /// This machine and this program's source, running on `threads` threads. Never fails:
    /// what cannot be found is "unknown" (or 1 core).
    pub fn here(threads: usize) -> Ran {
        Ran {
            commit: commit().unwrap_or_else(|| "unknown".into()),
            cpu: std::fs::read_to_string("/proc/cpuinfo")
                .ok()
                .and_then(|info| cpu_model(&info))
                .unwrap_or_else(|| "unknown".into()),
            cores: std::thread::available_parallelism().map_or(1, usize::from),
            threads,
        }
    }

    /// One line for the report: "commit abc1234, AMD EPYC 7B13 (2 cores), 2 threads".
    pub fn describe(&self) -> String {
        format!(
            "commit {}, {} ({} core{}), {} thread{}",
            self.commit,
            self.cpu,
            self.cores,
            if self.cores == 1 { "" } else { "s" },
            self.threads,
            if self.threads == 1 { "" } else { "s" }
        )
    }
}

/// The short commit of the source tree this crate was built from, if git can tell.
fn commit() -> Option<String> {
    let out = std::process::Command::new("git")
        .args(["-C", env!("CARGO_MANIFEST_DIR"), "rev-parse", "--short", "HEAD"])
        .stderr(std::process::Stdio::null())
        .output()
        .ok()?;
    let commit = String::from_utf8(out.stdout).ok()?.trim().to_string();
    (out.status.success() && !commit.is_empty()).then_some(commit)
}

/// The first "model name" of a `/proc/cpuinfo` text.
fn cpu_model(cpuinfo: &str) -> Option<String> {
    cpuinfo
        .lines()
        .filter_map(|line| line.split_once(':'))
        .find(|(key, _)| key.trim() == "model name")
        .map(|(_, value)| value.split_whitespace().collect::<Vec<_>>().join(" "))
        .filter(|model| !model.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cpu_model_is_the_first_model_name() {
        let info = "processor\t: 0\nvendor_id\t: AuthenticAMD\nmodel name\t: AMD  EPYC 7B13\nflags : x\n\
                    processor\t: 1\nmodel name\t: other\n";
        assert_eq!(cpu_model(info).as_deref(), Some("AMD EPYC 7B13"));
        assert_eq!(cpu_model("processor : 0\n"), None);
        assert_eq!(cpu_model("model name :   \n"), None);
    }

    #[test]
    fn here_never_fails_and_says_what_it_found() {
        let ran = Ran::here(3);
        assert_eq!(ran.threads, 3);
        assert!(ran.cores >= 1);
        assert!(!ran.commit.is_empty() && !ran.commit.contains(char::is_whitespace));
        assert!(ran.describe().ends_with("3 threads"), "{}", ran.describe());
    }
}
