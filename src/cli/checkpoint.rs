//! The checkpoint flags `train` and `dqn` share (`--checkpoint`, `--checkpoint-every`,
//! `--resume`), and the one rule of what `--checkpoint` may write over.
//!
//! A checkpoint is written again and again over its file, so a wrong `--checkpoint` would
//! silently destroy whatever the file held: a trained model, another run's checkpoint. It
//! writes only over nothing, or over a checkpoint of this very run (the same settings,
//! which the checkpoint records); anything else is refused before any work, as `--out X
//! --resume X` is.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{ArgGroup, Args};
use files::OutputPath;

/// The checkpoint flags of a training run (`train` counts games, `dqn` steps; each command
/// gives the help its unit and `--resume` the flags it conflicts with).
#[derive(Debug, Args)]
#[command(group(ArgGroup::new("checkpointing").args(["checkpoint", "resume"]).multiple(true)))]
pub struct CheckpointArgs {
    /// Write the run to this checkpoint file every --checkpoint-every games (`train`) or
    /// steps (`dqn`) and when it ends (atomically: a kill loses at most what came since the
    /// last one); `--resume FILE` continues it. It writes only over nothing or over a
    /// checkpoint of this same run: any other file is refused.
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    /// Games (`train`) or steps (`dqn`) between two checkpoints.
    #[arg(long, value_name = "N", requires = "checkpointing", value_parser = clap::value_parser!(u64).range(1..))]
    pub checkpoint_every: Option<u64>,
    /// Continue the run in this checkpoint file, with its settings; it goes on writing
    /// checkpoints to the same file unless --checkpoint names another. The flags that set up
    /// a run are refused with it: the checkpoint fixes them, so the run ends as if it had
    /// never stopped.
    #[arg(long, value_name = "FILE")]
    pub resume: Option<PathBuf>,
}

/// A kind of checkpoint: its container format and the unit of its `--checkpoint-every`.
pub struct CheckpointKind {
    /// The format its container names.
    pub format: &'static str,
    /// What `--checkpoint-every` counts: "games" or "steps".
    pub unit: &'static str,
}

impl CheckpointArgs {
    /// The checkpoint file the run writes (`--checkpoint`, else the `--resume` file),
    /// checked before any work beside `--out` (`out`, as checked): a file, not standard
    /// output, and not `--out`'s.
    pub fn output(&self, out: &Path, checked_out: &OutputPath, kind: &CheckpointKind) -> Result<Option<OutputPath>> {
        let path = self.checkpoint.as_ref().or(self.resume.as_ref());
        let checkpoint = path.map(OutputPath::check).transpose()?;
        anyhow::ensure!(
            !checkpoint.as_ref().is_some_and(OutputPath::is_stdout),
            "--checkpoint -: a checkpoint is written again every N {}, so it must be a file",
            kind.unit
        );
        super::stdout::claim_for_data(&[Some(checked_out), checkpoint.as_ref()])?;
        if let Some(path) = path {
            match (&self.checkpoint, files::refuse_same_file(out, path)) {
                (_, Ok(())) => {}
                // The checkpoint is written as well as read: it is not only an input.
                (Some(_), Err(_)) => anyhow::bail!(
                    "--out {} and --checkpoint {} are the same file: the model and the checkpoint need a file each",
                    out.display(),
                    path.display()
                ),
                (None, Err(e)) => return Err(anyhow::Error::new(e).context("--out and --resume")),
            }
        }
        Ok(checkpoint)
    }

    /// An error unless `--checkpoint` names nothing yet, or a checkpoint of this run:
    /// `this_run` says whether a file of the checkpoint's format holds it (the run's own
    /// `resume_run`, which compares the settings it records). The `--resume` file itself is
    /// this run's by definition.
    pub fn refuse_other_files(&self, kind: &CheckpointKind, this_run: impl FnOnce(&Path) -> bool) -> Result<()> {
        let Some(path) = &self.checkpoint else {
            return Ok(());
        };
        if self
            .resume
            .as_ref()
            .is_some_and(|r| files::refuse_same_file(r, path).is_err())
        {
            return Ok(());
        }
        match std::fs::symlink_metadata(path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
            Err(e) => return Err(e).with_context(|| format!("--checkpoint {}", path.display())),
            Ok(_) => {}
        }
        let held = match files::container::format_of(path, u64::MAX) {
            Some(format) if format == kind.format && this_run(path) => return Ok(()),
            Some(format) if format == kind.format => "a checkpoint of another run (other settings)".to_string(),
            Some(format) => format!("a {format} file{}", what_format_is(&format)),
            None => "not a checkpoint".to_string(),
        };
        anyhow::bail!(
            "--checkpoint {}: it is {held}, and writing checkpoints there would destroy it; \
             a checkpoint writes only over nothing or a checkpoint of the same run",
            path.display()
        )
    }
}

/// A few words on what a blockstack file format holds, for a refusal.
fn what_format_is(format: &str) -> &'static str {
    match format {
        neural::model::FORMAT => " (a trained network)",
        neural::relational::model::FORMAT => " (a trained relational policy)",
        agent::model::MODEL_FORMAT => " (a trained tabular model)",
        neural::checkpoint::CHECKPOINT_FORMAT | agent::checkpoint::CHECKPOINT_FORMAT => {
            " (another learner's checkpoint)"
        }
        _ => "",
    }
}
