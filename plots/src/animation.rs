//! Animated GIFs of picture sequences, one panel per sequence, side by side.
//!
//! The frames are any RGB pictures (the caller renders them); this module lays them out
//! under two caption lines, keeps the panels in step, subsamples long sequences and
//! stores only what changed between frames.

use std::path::Path;

use image::{Rgb, RgbImage, imageops};
use plotters::prelude::*;

use super::rgb::RgbBuffer;
use super::{FONT_FAMILY, INK, PlotError, Result, register_font};

/// One sequence of pictures to animate, with its caption.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Written above the panel, e.g. "Q-learner (paper), goal 1,0,2".
    pub caption: String,
    /// The pictures, the first state first (so `frames.len() - 1` steps).
    pub frames: Vec<RgbImage>,
    /// Appended to the step line on the last frame, e.g. ", goal reached"; may be empty.
    pub ending: String,
}

/// How an animation is captioned and timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GifOptions {
    /// Height of the caption font in pixels, 10 to 64; the caption shrinks (down to 10)
    /// to fit its panel's width.
    pub caption_px: u32,
    /// How long each frame shows, in milliseconds; at least 20 (browsers slow faster
    /// GIFs down).
    pub frame_ms: u32,
    /// How long the last frame shows before the animation loops, in milliseconds.
    pub last_frame_ms: u32,
    /// The most frames to write, at least 2; longer sequences are subsampled by
    /// [`frame_indices`].
    pub max_frames: usize,
}

impl Default for GifOptions {
    /// 14-pixel captions, 150 ms a frame, the end held 2 s, at most 120 frames: a
    /// 1000-step sequence of two small panels stays under a megabyte.
    fn default() -> Self {
        Self {
            caption_px: 14,
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

/// The pictures [`animated_gif`] writes, one per frame, whole (before the GIF stores only
/// what changed): for checking an animation, or for writing it in another format.
///
/// Errors: as [`animated_gif`], but for the size limit of a GIF.
pub fn canvases(panels: &[Panel], options: &GifOptions) -> Result<Vec<RgbImage>> {
    check(panels, options)?;
    register_font()?;
    let film = Film::new(panels, options.caption_px);
    frame_indices(film.longest(), options.max_frames)
        .into_iter()
        .map(|t| {
            film.canvas(t).map_err(|reason| PlotError::Draw {
                path: "an animation frame".into(),
                reason,
            })
        })
        .collect()
}

/// Writes an animated GIF of `panels` side by side to `path`, atomically, looping
/// forever, and returns the number of frames written.
///
/// Each panel shows its picture with two caption lines above it: the panel's caption,
/// then "step k of n", with the panel's [`Panel::ending`] on its final picture. All
/// panels advance together, one step per frame; a shorter panel holds its final picture
/// while a longer one goes on. Sequences longer than [`GifOptions::max_frames`] are
/// subsampled by [`frame_indices`] (on the longest panel's timeline), so a 1000-step
/// sequence still gives a small file; the step counter shows which steps were kept.
/// After the first frame, each frame stores only the rectangle that changed, with
/// unchanged pixels transparent.
///
/// Errors: no panels, a panel without pictures, options out of range, or a picture too
/// large for a GIF.
pub fn animated_gif(panels: &[Panel], options: &GifOptions, path: &Path) -> Result<usize> {
    check(panels, options)?;
    register_font()?;
    let film = Film::new(panels, options.caption_px);
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

/// The panels and their layout on the canvas.
struct Film<'a> {
    panels: &'a [Panel],
    panel_w: u32,
    frame_h: u32,
    font_px: u32,
}

/// Blank border around the panels, and the space between two panels, in pixels.
const PAD: u32 = 8;
const GAP: u32 = 16;

impl<'a> Film<'a> {
    /// Lays out `panels` with captions of `font_px` pixels.
    fn new(panels: &'a [Panel], font_px: u32) -> Self {
        let pictures = || panels.iter().flat_map(|p| &p.frames);
        Self {
            panels,
            panel_w: pictures().map(RgbImage::width).max().unwrap_or(1),
            frame_h: pictures().map(RgbImage::height).max().unwrap_or(1),
            font_px,
        }
    }

    /// Height of the two caption lines above each panel.
    fn caption_h(&self) -> u32 {
        2 * (self.font_px + 5) + 6
    }

    /// The canvas' width and height.
    fn size(&self) -> (u32, u32) {
        let n = self.panels.len() as u32;
        (
            2 * PAD + n * self.panel_w + (n - 1) * GAP,
            2 * PAD + self.caption_h() + self.frame_h,
        )
    }

    /// Pictures in the longest panel.
    fn longest(&self) -> usize {
        self.panels.iter().map(|p| p.frames.len()).max().unwrap_or(0)
    }

    /// The picture at time `t`: every panel at picture `t`, or its final one if shorter.
    fn canvas(&self, t: usize) -> std::result::Result<RgbImage, String> {
        let (width, height) = self.size();
        let mut canvas = RgbImage::from_pixel(width, height, Rgb([255, 255, 255]));
        let mut captions = Vec::new();
        for (p, panel) in self.panels.iter().enumerate() {
            let i = t.min(panel.frames.len() - 1);
            let x = PAD + p as u32 * (self.panel_w + GAP);
            imageops::replace(
                &mut canvas,
                &panel.frames[i],
                i64::from(x),
                i64::from(PAD + self.caption_h()),
            );
            let steps = panel.frames.len() - 1;
            let ending = if i < steps { "" } else { panel.ending.as_str() };
            captions.push((x, panel.caption.as_str(), format!("step {i} of {steps}{ending}")));
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

/// Validates the inputs of [`animated_gif`].
fn check(panels: &[Panel], options: &GifOptions) -> Result<()> {
    if panels.is_empty() {
        return Err(PlotError::Empty {
            what: "the list of panels".into(),
        });
    }
    if let Some(p) = panels.iter().find(|p| p.frames.is_empty()) {
        return Err(PlotError::Empty {
            what: format!("panel {:?}", p.caption),
        });
    }
    let bad = |reason: String| {
        Err(PlotError::Inconsistent {
            what: "the GIF options".into(),
            reason,
        })
    };
    if !(10..=64).contains(&options.caption_px) {
        return bad(format!("captions of {} pixels; use 10 to 64", options.caption_px));
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

    use super::super::test_support::{listing, temp_dir};
    use super::*;

    /// `steps + 1` pictures of a `side`-pixel square moving across a `7 x side` field, a
    /// few colours as in a rendered grid.
    fn moving(steps: usize, side: u32) -> Vec<RgbImage> {
        (0..=steps)
            .map(|s| {
                let at = (s as u32 % 7) * side;
                RgbImage::from_fn(7 * side, 7 * side, |x, y| {
                    if (at..at + side).contains(&x) && y >= 3 * side && y < 4 * side {
                        Rgb([200, 40, 40])
                    } else if (x / side + y / side).is_multiple_of(2) {
                        Rgb([235, 235, 235])
                    } else {
                        Rgb([250, 250, 250])
                    }
                })
            })
            .collect()
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
    fn one_panel_gives_one_frame_per_picture_and_holds_the_last() {
        let dir = temp_dir("gif-one");
        let frames = moving(11, 32);
        let states = frames.len();
        let path = dir.join("panel.gif");
        let panels = [Panel {
            caption: "a square".into(),
            frames,
            ending: ", done".into(),
        }];
        let options = GifOptions::default();
        let written = animated_gif(&panels, &options, &path).expect("gif");
        assert_eq!(written, states);
        let decoded = decode(&path);
        assert_eq!(decoded.len(), states);
        let delay = |f: &image::Frame| f.delay().numer_denom_ms();
        assert_eq!(delay(&decoded[0]), (150, 1));
        assert_eq!(delay(&decoded[states - 1]), (2000, 1));
        // The caption band has text in it: dark pixels above the pictures.
        let dark = decoded[0]
            .buffer()
            .rows()
            .take(40)
            .flatten()
            .filter(|p| p.0[..3].iter().all(|&c| c < 100))
            .count();
        assert!(dark > 50, "{dark} dark pixels in the caption band");
        // Delta frames composite back to exactly the pictures drawn (few colours: no
        // quantisation loss).
        let canvases = canvases(&panels, &options).expect("canvases");
        assert_eq!(canvases.len(), states);
        for (t, (frame, canvas)) in decoded.iter().zip(&canvases).enumerate() {
            let decoded = image::DynamicImage::ImageRgba8(frame.buffer().clone()).into_rgb8();
            assert!(decoded == *canvas, "frame {t} differs");
        }
        // The ending is written on the last frame only.
        assert!(canvases[states - 1] != canvases[states - 2]);
        assert_eq!(listing(&dir), ["panel.gif"]);
    }

    #[test]
    fn long_panels_side_by_side_are_subsampled_and_small() {
        let dir = temp_dir("gif-two");
        let path = dir.join("two.gif");
        let panels = [
            Panel {
                caption: "1000 steps: the caption is long and must shrink to fit, or else be cut short".into(),
                frames: moving(1000, 32),
                ending: String::new(),
            },
            Panel {
                caption: "short".into(),
                frames: moving(30, 32),
                ending: ", done".into(),
            },
        ];
        let options = GifOptions::default();
        let written = animated_gif(&panels, &options, &path).expect("gif");
        assert_eq!(written, options.max_frames);
        let frames = decode(&path);
        assert_eq!(frames.len(), options.max_frames);
        let (w, h) = frames[0].buffer().dimensions();
        let single = &panels[0].frames[0];
        assert!(w > 2 * single.width() && h > single.height(), "{w}x{h}");
        let size = std::fs::metadata(&path).expect("gif").len();
        assert!(size < 1_000_000, "{size} bytes");
    }

    #[test]
    fn bad_inputs_are_errors() {
        let dir = temp_dir("gif-bad");
        let path = dir.join("bad.gif");
        let ok = Panel {
            caption: "ok".into(),
            frames: moving(3, 8),
            ending: String::new(),
        };
        let options = GifOptions::default();
        assert!(matches!(
            animated_gif(&[], &options, &path),
            Err(PlotError::Empty { .. })
        ));
        let empty = Panel {
            caption: "empty".into(),
            frames: vec![],
            ending: String::new(),
        };
        let err = animated_gif(&[ok.clone(), empty], &options, &path).unwrap_err();
        assert!(err.to_string().contains("\"empty\""), "{err}");
        for bad in [
            GifOptions {
                caption_px: 0,
                ..options
            },
            GifOptions {
                caption_px: 1000,
                ..options
            },
            GifOptions { frame_ms: 0, ..options },
            GifOptions {
                max_frames: 1,
                ..options
            },
        ] {
            let err = animated_gif(std::slice::from_ref(&ok), &bad, &path).unwrap_err();
            assert!(matches!(err, PlotError::Inconsistent { .. }), "{err}");
            let err = canvases(std::slice::from_ref(&ok), &bad).unwrap_err();
            assert!(matches!(err, PlotError::Inconsistent { .. }), "{err}");
        }
        // Too wide for a GIF: many wide panels (of thin pictures, to spare memory).
        let wide = vec![
            Panel {
                frames: vec![RgbImage::new(1000, 1)],
                ..ok.clone()
            };
            66
        ];
        let err = animated_gif(&wide, &options, &path).unwrap_err();
        assert!(err.to_string().contains("larger than a GIF"), "{err}");
        assert!(listing(&dir).is_empty());
        // A single picture is a one-frame GIF.
        let still = Panel {
            caption: String::new(),
            frames: vec![ok.frames[0].clone()],
            ending: String::new(),
        };
        assert_eq!(animated_gif(&[still], &options, &path).expect("gif"), 1);
        assert_eq!(decode(&path).len(), 1);
    }
}
