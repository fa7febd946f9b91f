//! Animated GIFs of episodes of the block world, one panel per episode, side by side: the
//! part of an episode picture that knows blocks (rendering a state, saying whether the goal
//! was reached), over the `plots` crate's animation of picture sequences.

use std::path::Path;

use plots::{Panel, PlotError};
use sim::Observation;

/// One episode to animate: its caption and the observation after each step, the start
/// first (so `observations.len() - 1` steps).
#[derive(Clone, Debug, PartialEq)]
pub struct EpisodeFrames {
    /// Written above the panel, e.g. "Q-learner (paper), goal 1,0,2".
    pub caption: String,
    /// The states of the episode, the start first.
    pub observations: Vec<Observation>,
}

/// How an episode GIF is drawn and timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GifOptions {
    /// Side of a grid cell in pixels, 8 to 128.
    pub cell_px: u32,
    /// How long each frame shows, in milliseconds; at least 20 (browsers slow faster
    /// GIFs down).
    pub frame_ms: u32,
    /// How long the last frame shows before the animation loops, in milliseconds.
    pub last_frame_ms: u32,
    /// The most frames to write, at least 2; longer episodes are subsampled by
    /// [`plots::frame_indices`].
    pub max_frames: usize,
}

impl Default for GifOptions {
    /// 32-pixel cells, 150 ms a frame, the end held 2 s, at most 120 frames: a 1000-step
    /// episode of two panels stays under a megabyte.
    fn default() -> Self {
        Self {
            cell_px: 32,
            frame_ms: 150,
            last_frame_ms: 2000,
            max_frames: 120,
        }
    }
}

impl GifOptions {
    /// The animation's options: captions sized to the cells.
    fn animation(&self) -> plots::GifOptions {
        plots::GifOptions {
            caption_px: (self.cell_px * 4 / 9).clamp(11, 18),
            frame_ms: self.frame_ms,
            last_frame_ms: self.last_frame_ms,
            max_frames: self.max_frames,
        }
    }
}

/// Writes an animated GIF of `episodes` side by side to `path`, atomically, looping
/// forever, and returns the number of frames written.
///
/// Each panel shows [`sim::render::frame`] of the episode's state with two caption lines
/// above it: the episode's caption, then "step k of n", with "goal reached" or "goal not
/// reached" on the final state. The panels advance together and long episodes are
/// subsampled, as [`plots::animated_gif`] says.
///
/// Errors: no episodes, an episode without observations, options out of range, or a
/// picture too large for a GIF.
pub fn episode_gif(episodes: &[EpisodeFrames], options: &GifOptions, path: &Path) -> Result<usize, PlotError> {
    plots::animated_gif(&panels(episodes, options)?, &options.animation(), path)
}

/// The panels of `episodes`: each state rendered, and the ending said on the last.
fn panels(episodes: &[EpisodeFrames], options: &GifOptions) -> Result<Vec<Panel>, PlotError> {
    if episodes.is_empty() {
        return Err(PlotError::Empty {
            what: "the list of episodes".into(),
        });
    }
    if let Some(e) = episodes.iter().find(|e| e.observations.is_empty()) {
        return Err(PlotError::Empty {
            what: format!("episode {:?}", e.caption),
        });
    }
    if !(8..=128).contains(&options.cell_px) {
        return Err(PlotError::Inconsistent {
            what: "the GIF options".into(),
            reason: format!("cells of {} pixels; use 8 to 128", options.cell_px),
        });
    }
    Ok(episodes
        .iter()
        .map(|e| {
            let last = e.observations.last().expect("checked: not empty");
            Panel {
                caption: e.caption.clone(),
                frames: e
                    .observations
                    .iter()
                    .map(|o| sim::render::frame(o, options.cell_px))
                    .collect(),
                ending: if last.goal.holds(&last.state) {
                    ", goal reached"
                } else {
                    ", goal not reached"
                }
                .into(),
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use image::AnimationDecoder;
    use image::codecs::gif::GifDecoder;
    use sim::{Action, Env, EnvConfig, Goal};

    use super::*;

    /// The files in `dir`, sorted: no temporaries may be left behind.
    fn listing(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .expect("dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    /// An episode of `steps` seeded random actions (or fewer, if it ends), start first.
    fn episode(seed: u64, steps: usize) -> Vec<Observation> {
        let goal: Goal = "1,0,2".parse().expect("goal");
        let mut env = Env::new(EnvConfig {
            horizon: steps as u32,
            ..EnvConfig::with_goal(goal)
        })
        .expect("env");
        let mut observations = vec![env.reset(seed)];
        let n = env.action_count();
        let mut rng = sim::seeding::rng(seed);
        while !env.is_over() {
            let i = rand::RngExt::random_range(&mut rng, 0..n);
            observations.push(
                env.step(Action::from_index(i, 3).expect("action"))
                    .expect("step")
                    .observation,
            );
        }
        observations
    }

    fn decode(path: &Path) -> Vec<image::Frame> {
        let file = std::io::BufReader::new(std::fs::File::open(path).expect("gif"));
        GifDecoder::new(file)
            .expect("decodes")
            .into_frames()
            .collect_frames()
            .expect("frames")
    }

    #[test]
    fn one_episode_gives_one_frame_per_state_and_holds_the_last() {
        let dir = tempfile::tempdir().expect("temp dir");
        let observations = episode(3, 12);
        let states = observations.len();
        let path = dir.path().join("episode.gif");
        let episodes = [EpisodeFrames {
            caption: "random agent".into(),
            observations,
        }];
        let written = episode_gif(&episodes, &GifOptions::default(), &path).expect("gif");
        assert_eq!(written, states);
        let frames = decode(&path);
        assert_eq!(frames.len(), states);
        let delay = |f: &image::Frame| f.delay().numer_denom_ms();
        assert_eq!(delay(&frames[0]), (150, 1));
        assert_eq!(delay(&frames[states - 1]), (2000, 1));
        // The caption band has text in it: dark pixels above the grid.
        let first = frames[0].buffer();
        let dark = first
            .rows()
            .take(40)
            .flatten()
            .filter(|p| p.0[..3].iter().all(|&c| c < 100))
            .count();
        assert!(dark > 50, "{dark} dark pixels in the caption band");
        // Delta frames composite back to exactly the pictures drawn (few colours: no
        // quantisation loss).
        let options = GifOptions::default();
        let canvases =
            plots::canvases(&panels(&episodes, &options).expect("panels"), &options.animation()).expect("canvases");
        for (t, frame) in frames.iter().enumerate() {
            let decoded = image::DynamicImage::ImageRgba8(frame.buffer().clone()).into_rgb8();
            assert!(decoded == canvases[t], "frame {t} differs");
        }
        assert_eq!(listing(dir.path()), ["episode.gif"]);
    }

    #[test]
    fn long_episodes_side_by_side_are_subsampled_and_small() {
        let dir = tempfile::tempdir().expect("temp dir");
        let long = episode(5, 1000);
        assert_eq!(
            long.len(),
            1001,
            "a random agent rarely finishes in 1000 steps from this seed"
        );
        let short = episode(5, 30);
        let path = dir.path().join("two.gif");
        let episodes = [
            EpisodeFrames {
                caption: "random agent, 1000 steps: the caption is long and must shrink to fit, or else be cut short"
                    .into(),
                observations: long,
            },
            EpisodeFrames {
                caption: "short".into(),
                observations: short,
            },
        ];
        let options = GifOptions::default();
        let written = episode_gif(&episodes, &options, &path).expect("gif");
        assert_eq!(written, options.max_frames);
        let frames = decode(&path);
        assert_eq!(frames.len(), options.max_frames);
        let (w, h) = frames[0].buffer().dimensions();
        let single = sim::render::frame(&episodes[0].observations[0], options.cell_px);
        assert!(w > 2 * single.width() && h > single.height(), "{w}x{h}");
        let size = std::fs::metadata(&path).expect("gif").len();
        assert!(size < 1_000_000, "{size} bytes");
    }

    #[test]
    fn bad_inputs_are_errors() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("bad.gif");
        let ok = EpisodeFrames {
            caption: "ok".into(),
            observations: episode(1, 3),
        };
        let options = GifOptions::default();
        assert!(matches!(
            episode_gif(&[], &options, &path),
            Err(PlotError::Empty { .. })
        ));
        let empty = EpisodeFrames {
            caption: "empty".into(),
            observations: vec![],
        };
        let err = episode_gif(&[ok.clone(), empty], &options, &path).unwrap_err();
        assert!(err.to_string().contains("\"empty\""), "{err}");
        for bad in [
            GifOptions { cell_px: 0, ..options },
            GifOptions {
                cell_px: 1000,
                ..options
            },
            GifOptions { frame_ms: 0, ..options },
            GifOptions {
                max_frames: 1,
                ..options
            },
        ] {
            let err = episode_gif(std::slice::from_ref(&ok), &bad, &path).unwrap_err();
            assert!(matches!(err, PlotError::Inconsistent { .. }), "{err}");
        }
        // Too wide for a GIF: many panels of large cells.
        let wide = vec![ok.clone(); 200];
        let err = episode_gif(
            &wide,
            &GifOptions {
                cell_px: 128,
                ..options
            },
            &path,
        )
        .unwrap_err();
        assert!(err.to_string().contains("larger than a GIF"), "{err}");
        assert!(listing(dir.path()).is_empty());
        // A single state is a one-frame GIF.
        let still = EpisodeFrames {
            caption: String::new(),
            observations: vec![ok.observations[0].clone()],
        };
        assert_eq!(episode_gif(&[still], &options, &path).expect("gif"), 1);
        assert_eq!(decode(&path).len(), 1);
    }
}
