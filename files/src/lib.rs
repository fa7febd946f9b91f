//! How blockstack writes and reads files. Every command's outputs and every reader of a
//! blockstack file go through this crate, so that each rule holds everywhere:
//!
//! - [`output`]: a destination is checked before any work starts; a regular file is
//!   replaced atomically through a hidden temporary file, a device, FIFO or socket is
//!   written directly, `-` is standard output, symbolic links are followed; an output
//!   that is one of the inputs is refused ([`refuse_same_file`]). Appended files
//!   (recordings) are written in place.
//! - [`temp`]: every live temporary file is listed, and [`remove_temp_files`] removes them
//!   all: the binary calls it when Ctrl-C or SIGTERM ends the process.
//! - [`input`]: every read is bounded by the largest file of its kind; `/dev/zero` given
//!   as a model is refused, never read until memory runs out.
//! - [`container`]: the model container, safetensors (named tensors) with blockstack's
//!   metadata (format, version, a CRC-32, the writer's JSON), readable from numpy.
//!
//! It is the bottom layer: it depends on no other blockstack crate.
//!
//! ```
//! let dir = std::env::temp_dir().join(format!("files-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir).unwrap();
//! let out = files::OutputPath::check(dir.join("hello.txt"))?;
//! out.write(b"hello\n")?;
//! assert_eq!(std::fs::read(dir.join("hello.txt")).unwrap(), b"hello\n");
//! // A missing folder is refused before anything is done.
//! let err = files::OutputPath::check(dir.join("missing/hello.txt")).unwrap_err();
//! assert!(err.to_string().contains("does not exist"));
//! # std::fs::remove_dir_all(&dir).unwrap();
//! # Ok::<(), files::FilesError>(())
//! ```

pub mod container;
pub mod error;
pub mod input;
pub mod output;
pub mod temp;

pub use container::{Container, Dtype, Element, Expect, Tensor};
pub use error::{Bytes, FilesError, ReadProblem, Result};
pub use input::{BoundedReader, digest_file, open_bounded};
pub use output::{Destination, Output, OutputPath, STDOUT, Special, prepare_folder, refuse_same_file, write};
pub use temp::{live_temp_files, remove_temp_files};
