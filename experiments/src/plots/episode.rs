//! Animated GIFs of episodes, one panel per episode, side by side.

use std::path::Path;

use image::{Rgb, RgbImage, imageops};
use plotters::prelude::*;
use sim::Observation;

use super::rgb::RgbBuffer;
use super::{FONT_FAMILY, INK, PlotError, Result, register_font};

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
    /// [`frame_indices`].
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

/// Which of `len` states (indices `0..len`) to show when at most `max_frames` may be
/// shown: all of them if they fit, otherwise `max_frames` indices spread evenly,
/// `round(i * (len - 1) / (max_frames - 1))` for `i` in `0..max_frames`, so the start
/// and the final state always appear and the steps skipped between frames differ by at
/// most one. `max_frames` below 2 counts as 2; `len` 0 gives no frames.
pub fn frame_indices(len: usize, max_frames: usize) -> Vec<usize> {
    let max_frames = max_frames.max(2);
    if len <= max_frames {
        return (0..len).collect();
    }
    let (last, gaps) = ((len - 1) as u128, (max_frames - 1) as u128);
    // Integer rounding of i * last / gaps, exact for any length.
    (0..max_frames as u128)
        .map(|i| ((2 * i * last + gaps) / (2 * gaps)) as usize)
        .collect()
}

/// Writes an animated GIF of `episodes` side by side to `path`, atomically, looping
/// forever, and returns the number of frames written.
///
/// Each panel shows [`sim::render::frame`] of the episode's state with two caption lines
/// above it: the episode's caption, then "step k of n", with "goal reached" or "goal not
/// reached" on the final state. All panels advance together, one step per frame;
/// a shorter episode holds its final state while a longer one goes on. Episodes longer
/// than [`GifOptions::max_frames`] states are subsampled by [`frame_indices`] (on the
/// longest episode's timeline), so a 1000-step episode still gives a small file; the
/// step counter shows which steps were kept. After the first frame, each frame stores
/// only the rectangle that changed, with unchanged pixels transparent.
///
/// Errors: no episodes, an episode without observations, options out of range, or a
/// picture too large for a GIF.
pub fn episode_gif(episodes: &[EpisodeFrames], options: &GifOptions, path: &Path) -> Result<usize> {
    check(episodes, options)?;
    register_font()?;
    let film = Film::new(episodes, options.cell_px);
    let (width, height) = film.size();
    let (Ok(w16), Ok(h16)) = (u16::try_from(width), u16::try_from(height)) else {
        return Err(PlotError::Inconsistent {
            what: path.display().to_string(),
            reason: format!("a {width}x{height} picture is larger than a GIF can hold (65535 pixels a side)"),
        });
    };
    let encode_error = |e: &dyn std::fmt::Display| PlotError::Encode {
        path: path.display().to_string(),
        reason: e.to_string(),
    };
    let indices = frame_indices(film.longest(), options.max_frames);
    let mut bytes = Vec::new();
    let mut encoder = gif::Encoder::new(&mut bytes, w16, h16, &[]).map_err(|e| encode_error(&e))?;
    encoder
        .set_repeat(gif::Repeat::Infinite)
        .map_err(|e| encode_error(&e))?;
    let mut previous: Option<RgbImage> = None;
    for (k, &t) in indices.iter().enumerate() {
        let canvas = film.canvas(t).map_err(|e| encode_error(&e))?;
        let ms = if k + 1 == indices.len() {
            options.last_frame_ms.max(options.frame_ms)
        } else {
            options.frame_ms
        };
        let frame = delta_frame(previous.as_ref(), &canvas, ms);
        encoder.write_frame(&frame).map_err(|e| encode_error(&e))?;
        previous = Some(canvas);
    }
    encoder.into_inner().map_err(|e| encode_error(&e))?;
    files::write(path, &bytes)?;
    Ok(indices.len())
}

/// The episodes' frames and the layout of the panels on the canvas.
struct Film<'a> {
    episodes: &'a [EpisodeFrames],
    /// Each episode's rendered states.
    frames: Vec<Vec<RgbImage>>,
    panel_w: u32,
    frame_h: u32,
    font_px: u32,
}

/// Blank border around the panels, and the space between two panels, in pixels.
const PAD: u32 = 8;
const GAP: u32 = 16;

impl<'a> Film<'a> {
    /// Renders every state of `episodes` with cells of `cell` pixels.
    fn new(episodes: &'a [EpisodeFrames], cell: u32) -> Self {
        let frames: Vec<Vec<RgbImage>> = episodes
            .iter()
            .map(|e| e.observations.iter().map(|o| sim::render::frame(o, cell)).collect())
            .collect();
        Self {
            episodes,
            panel_w: frames.iter().flatten().map(RgbImage::width).max().unwrap_or(1),
            frame_h: frames.iter().flatten().map(RgbImage::height).max().unwrap_or(1),
            frames,
            font_px: (cell * 4 / 9).clamp(11, 18),
        }
    }

    /// Height of the two caption lines above each panel.
    fn caption_h(&self) -> u32 {
        2 * (self.font_px + 5) + 6
    }

    /// The canvas' width and height.
    fn size(&self) -> (u32, u32) {
        let n = self.episodes.len() as u32;
        (
            2 * PAD + n * self.panel_w + (n - 1) * GAP,
            2 * PAD + self.caption_h() + self.frame_h,
        )
    }

    /// States in the longest episode.
    fn longest(&self) -> usize {
        self.frames.iter().map(Vec::len).max().unwrap_or(0)
    }

    /// The picture at time `t`: every episode at state `t`, or its final state if shorter.
    fn canvas(&self, t: usize) -> std::result::Result<RgbImage, String> {
        let (width, height) = self.size();
        let mut canvas = RgbImage::from_pixel(width, height, Rgb([255, 255, 255]));
        let mut captions = Vec::new();
        for (p, (episode, panel)) in self.episodes.iter().zip(&self.frames).enumerate() {
            let i = t.min(panel.len() - 1);
            let x = PAD + p as u32 * (self.panel_w + GAP);
            imageops::replace(&mut canvas, &panel[i], i64::from(x), i64::from(PAD + self.caption_h()));
            let steps = panel.len() - 1;
            let obs = &episode.observations[i];
            let status = if i < steps {
                ""
            } else if obs.goal.holds(&obs.state) {
                ", goal reached"
            } else {
                ", goal not reached"
            };
            captions.push((x, episode.caption.as_str(), format!("step {i} of {steps}{status}")));
        }
        draw_captions(canvas, &captions, self.font_px, self.panel_w)
    }
}

/// The GIF frame that turns `previous` into `current` (both the canvas' size): the
/// bounding rectangle of the changed pixels, unchanged ones transparent, kept on screen
/// for `ms` milliseconds. The first frame (no `previous`) is the whole canvas; a frame
/// equal to the previous one is a single transparent pixel, which still holds the delay.
fn delta_frame(previous: Option<&RgbImage>, current: &RgbImage, ms: u32) -> gif::Frame<'static> {
    let (w, h) = current.dimensions();
    let changed = |x: u32, y: u32| previous.is_none_or(|p| p.get_pixel(x, y) != current.get_pixel(x, y));
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for (x, y, _) in current.enumerate_pixels() {
        if changed(x, y) {
            (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1));
        }
    }
    if x0 >= x1 {
        (x0, y0, x1, y1) = (0, 0, 1, 1);
    }
    let mut rgba = Vec::with_capacity(4 * ((x1 - x0) * (y1 - y0)) as usize);
    for y in y0..y1 {
        for x in x0..x1 {
            let [r, g, b] = current.get_pixel(x, y).0;
            rgba.extend_from_slice(&if changed(x, y) { [r, g, b, 255] } else { [0, 0, 0, 0] });
        }
    }
    // The canvas fits u16 (checked by the caller), so its parts do.
    let (fw, fh) = ((x1 - x0) as u16, (y1 - y0) as u16);
    let mut frame = gif::Frame::from_rgba_speed(fw, fh, &mut rgba, 10);
    frame.left = x0 as u16;
    frame.top = y0 as u16;
    frame.delay = u16::try_from(ms / 10).unwrap_or(u16::MAX);
    frame.dispose = gif::DisposalMethod::Keep;
    frame
}

/// Validates the inputs of [`episode_gif`].
fn check(episodes: &[EpisodeFrames], options: &GifOptions) -> Result<()> {
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
    let bad = |reason: String| {
        Err(PlotError::Inconsistent {
            what: "the GIF options".into(),
            reason,
        })
    };
    if !(8..=128).contains(&options.cell_px) {
        return bad(format!("cells of {} pixels; use 8 to 128", options.cell_px));
    }
    if options.frame_ms < 20 {
        return bad(format!("frames of {} ms; use at least 20", options.frame_ms));
    }
    if options.max_frames < 2 {
        return bad(format!("at most {} frames; allow at least 2", options.max_frames));
    }
    Ok(())
}

/// Draws each panel's two caption lines onto `canvas`: the caption (its font shrunk to fit
/// the panel's `width` where needed, down to 10 pixels, then cut short with an
/// ellipsis) and the step line in grey.
fn draw_captions(
    canvas: RgbImage,
    captions: &[(u32, &str, String)],
    font_px: u32,
    width: u32,
) -> std::result::Result<RgbImage, String> {
    let mut buffer = RgbBuffer::from_image(canvas);
    {
        let area = buffer.backend().into_drawing_area();
        for (x, caption, step) in captions {
            let mut px = font_px;
            let fits = |px: u32, text: &str| {
                (FONT_FAMILY, px)
                    .into_font()
                    .box_size(text)
                    .map(|(w, _)| w <= width)
                    .unwrap_or(true)
            };
            while px > 10 && !fits(px, caption) {
                px -= 1;
            }
            // Still too wide at the smallest size: cut it short, marked with an ellipsis.
            let mut text = caption.to_string();
            let mut kept: Vec<char> = caption.chars().collect();
            while !kept.is_empty() && !fits(px, &text) {
                kept.pop();
                text = format!("{}…", kept.iter().collect::<String>().trim_end());
            }
            let (x, y) = (*x as i32, PAD as i32);
            area.draw(&Text::new(text, (x, y), (FONT_FAMILY, px).into_font().color(&INK)))
                .map_err(|e| e.to_string())?;
            area.draw(&Text::new(
                step.as_str(),
                (x, y + font_px as i32 + 5),
                (FONT_FAMILY, font_px).into_font().color(&RGBColor(90, 90, 90)),
            ))
            .map_err(|e| e.to_string())?;
        }
        area.present().map_err(|e| e.to_string())?;
    }
    Ok(buffer.into_image())
}

#[cfg(test)]
mod tests {
    use image::AnimationDecoder;
    use image::codecs::gif::GifDecoder;
    use sim::{Action, Env, EnvConfig, Goal};

    use super::super::test_support::{listing, temp_dir};
    use super::*;

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
    fn frame_indices_keep_both_ends_and_spread_evenly() {
        assert_eq!(frame_indices(0, 10), Vec::<usize>::new());
        assert_eq!(frame_indices(1, 10), [0]);
        assert_eq!(frame_indices(5, 10), [0, 1, 2, 3, 4]);
        assert_eq!(frame_indices(11, 6), [0, 2, 4, 6, 8, 10]);
        assert_eq!(frame_indices(5, 0), [0, 4]);
        for (len, max) in [(1001, 120), (1000, 7), (121, 120), (10_000_000, 3)] {
            let idx = frame_indices(len, max);
            assert_eq!(idx.len(), max);
            assert_eq!((idx[0], idx[max - 1]), (0, len - 1));
            let gaps: Vec<usize> = idx.windows(2).map(|w| w[1] - w[0]).collect();
            let (lo, hi) = (gaps.iter().min().expect("gaps"), gaps.iter().max().expect("gaps"));
            assert!(*lo >= 1 && hi - lo <= 1, "{len}/{max}: gaps {lo}..{hi}");
        }
    }

    #[test]
    fn one_episode_gives_one_frame_per_state_and_holds_the_last() {
        let dir = temp_dir("gif-one");
        let observations = episode(3, 12);
        let states = observations.len();
        let path = dir.join("episode.gif");
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
        let film = Film::new(&episodes, GifOptions::default().cell_px);
        for (t, frame) in frames.iter().enumerate() {
            let decoded = image::DynamicImage::ImageRgba8(frame.buffer().clone()).into_rgb8();
            assert!(decoded == film.canvas(t).expect("canvas"), "frame {t} differs");
        }
        assert_eq!(listing(&dir), ["episode.gif"]);
    }

    #[test]
    fn long_episodes_side_by_side_are_subsampled_and_small() {
        let dir = temp_dir("gif-two");
        let long = episode(5, 1000);
        assert_eq!(
            long.len(),
            1001,
            "a random agent rarely finishes in 1000 steps from this seed"
        );
        let short = episode(5, 30);
        let path = dir.join("two.gif");
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
        let dir = temp_dir("gif-bad");
        let path = dir.join("bad.gif");
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
        assert!(listing(&dir).is_empty());
        // A single state is a one-frame GIF.
        let still = EpisodeFrames {
            caption: String::new(),
            observations: vec![ok.observations[0]],
        };
        assert_eq!(episode_gif(&[still], &options, &path).expect("gif"), 1);
        assert_eq!(decode(&path).len(), 1);
    }
}
