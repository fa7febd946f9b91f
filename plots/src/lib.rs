//! Pictures for reports: charts as PNG and SVG, picture sequences as animated GIFs.
//!
//! A crate of its own, knowing nothing of blocks: it draws numbers and pictures it is
//! given, so any report (the reproduction's, a sweep's, a single run's) can use it.
//!
//! | function | picture | used for |
//! | --- | --- | --- |
//! | [`learning_curve`] | failures and mean steps against training games, two panels, several series and reference values | E4 |
//! | [`box_plot`] | steps per arm: boxes, whiskers, outliers, reference markers | E5, E6 |
//! | [`bar_chart`] | one bar per agent, optional intervals, second values, optimum line | E7 |
//! | [`animated_gif`] | one or more picture sequences side by side, animated | episodes |
//! | [`curves_chart`] | several learners' curves against training, one line each | E8 |
//!
//! Every function is pure: it takes the data, validates it, and writes its files atomically
//! (through the output helper, [`files::write`]). Charts are written twice, `<stem>.png` and
//! `<stem>.svg`, and the paths come back in [`ChartFiles`]. Odd data (an empty list, a
//! non-finite value, a count above its total) is a [`PlotError`], never a panic; a single
//! point or all-equal values give a picture with a padded axis.
//!
//! # Why a bundled font
//!
//! Text is drawn with DejaVu Sans, bundled in `assets/` (Bitstream Vera licence, beside
//! it) and registered once with plotters' `ab_glyph` renderer: nothing here reads system
//! fonts, so CI machines without fonts draw the same pictures, and a picture does not
//! change with the fonts a machine happens to have. PNGs are rendered by plotters into an
//! RGB buffer and encoded by `image` (so the build holds one `image` version); GIFs are
//! encoded by `gif`, storing only what changed between frames.

mod animation;
mod bars;
mod boxes;
mod curves;
mod learning;

pub use animation::{GifOptions, Panel, animated_gif, canvases, frame_indices};
pub use bars::{Bar, BarChart, Reference, bar_chart};
pub use boxes::{Arm, BoxPlot, box_plot};
pub use curves::{CurvesChart, Series, curves_chart};
pub use learning::{LearningCurve, LearningPoint, LearningSeries, SeriesStyle, learning_curve};

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use rgb::RgbBuffer;
use thiserror::Error;

/// The bundled font, DejaVu Sans (see `assets/DejaVuSans-LICENSE.txt`).
const FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// The family name the bundled font is registered under; plotters' default family.
const FONT_FAMILY: &str = "sans-serif";

/// The largest magnitude a plotted value may have: far above any step count, and far
/// enough below `f64::MAX` that axis arithmetic (spans, padding, tick steps) stays finite.
pub const MAX_VALUE: f64 = 1e15;

/// What can go wrong while drawing or writing a picture.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PlotError {
    /// Nothing to draw: an empty list of points, arms, bars or observations.
    #[error("nothing to plot: {what} is empty")]
    Empty {
        /// What was empty ("points", "arms", ...).
        what: String,
    },
    /// A value that cannot be placed on an axis: NaN, infinite or beyond [`MAX_VALUE`].
    #[error("{what} is {}, which cannot be plotted: values must be finite and at most {MAX_VALUE:e} in size", number_label(*value))]
    BadValue {
        /// Which value ("bar \"random\" value", ...).
        what: String,
        /// The value given.
        value: f64,
    },
    /// Inconsistent input, e.g. more failures than test episodes or an interval whose low
    /// end is above its high end.
    #[error("cannot plot {what}: {reason}")]
    Inconsistent {
        /// What is inconsistent.
        what: String,
        /// Why.
        reason: String,
    },
    /// The bundled font could not be registered (a corrupt build).
    #[error("the bundled font cannot be loaded")]
    Font,
    /// Drawing failed inside plotters.
    #[error("cannot draw {path}: {reason}")]
    Draw {
        /// The file being drawn.
        path: String,
        /// plotters' reason.
        reason: String,
    },
    /// Encoding the PNG or GIF failed.
    #[error("cannot encode {path}: {reason}")]
    Encode {
        /// The file being encoded.
        path: String,
        /// The encoder's reason.
        reason: String,
    },
    /// Writing a file failed.
    #[error(transparent)]
    Write(#[from] files::FilesError),
}

/// Shorthand for results whose error is a [`PlotError`].
pub type Result<T, E = PlotError> = std::result::Result<T, E>;

/// The two files a chart is written to.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChartFiles {
    /// `<stem>.png`, a bitmap for the README and quick viewing.
    pub png: PathBuf,
    /// `<stem>.svg`, the same chart as vector graphics.
    pub svg: PathBuf,
}

/// Registers the bundled font with plotters, once per process.
fn register_font() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok { Ok(()) } else { Err(PlotError::Font) }
}

/// A chart that can draw itself on any plotters backend.
trait Chart {
    /// Width and height in pixels.
    fn size(&self) -> (u32, u32);

    /// Draws the whole chart on `root`, already filled white.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<(), DB>;
}

/// Draws `chart` into `<stem>.png` and `<stem>.svg`.
fn write_chart(chart: &impl Chart, stem: &Path) -> Result<ChartFiles> {
    register_font()?;
    let files = ChartFiles {
        png: with_extension(stem, "png"),
        svg: with_extension(stem, "svg"),
    };
    let (w, h) = chart.size();

    let mut pixels = RgbBuffer::new(w, h);
    render(chart, pixels.backend(), &files.png)?;
    let png = pixels.encode_png().map_err(|reason| PlotError::Encode {
        path: files.png.display().to_string(),
        reason,
    })?;
    files::write(&files.png, &png)?;

    let mut svg = String::new();
    render(chart, SVGBackend::with_string(&mut svg, (w, h)), &files.svg)?;
    files::write(&files.svg, svg.as_bytes())?;
    Ok(files)
}

/// Fills `backend` white, draws `chart` and finishes the drawing.
fn render<DB: DrawingBackend>(chart: &impl Chart, backend: DB, path: &Path) -> Result<()> {
    let root = backend.into_drawing_area();
    let draw_error = |e: &dyn std::fmt::Display| PlotError::Draw {
        path: path.display().to_string(),
        reason: e.to_string(),
    };
    root.fill(&WHITE).map_err(|e| draw_error(&e))?;
    chart.draw(&root).map_err(|e| draw_error(&e))?;
    root.present().map_err(|e| draw_error(&e))
}

/// `stem` with `.ext` appended (not replacing a dotted part of the stem, as
/// [`Path::with_extension`] would).
fn with_extension(stem: &Path, ext: &str) -> PathBuf {
    let mut name = OsString::from(stem.as_os_str());
    name.push(".");
    name.push(ext);
    PathBuf::from(name)
}

/// Drawing into an RGB buffer owned here, then encoding it with `image`.
mod rgb {
    use plotters::backend::RGBPixel;
    use plotters::prelude::BitMapBackend;

    /// An RGB pixel buffer that plotters draws into.
    pub(super) struct RgbBuffer {
        width: u32,
        height: u32,
        data: Vec<u8>,
    }

    impl RgbBuffer {
        /// A `width x height` buffer, black until drawn on.
        pub(super) fn new(width: u32, height: u32) -> Self {
            Self {
                width,
                height,
                data: vec![0; 3 * width as usize * height as usize],
            }
        }

        /// Wraps an existing RGB image (e.g. to draw captions on it).
        pub(super) fn from_image(image: image::RgbImage) -> Self {
            Self {
                width: image.width(),
                height: image.height(),
                data: image.into_raw(),
            }
        }

        /// A plotters backend drawing into this buffer.
        pub(super) fn backend(&mut self) -> BitMapBackend<'_, RGBPixel> {
            BitMapBackend::with_buffer_and_format(&mut self.data, (self.width, self.height))
                .expect("the buffer is sized for its dimensions")
        }

        /// The buffer as an image.
        pub(super) fn into_image(self) -> image::RgbImage {
            image::RgbImage::from_raw(self.width, self.height, self.data)
                .expect("the buffer is sized for its dimensions")
        }

        /// The buffer as PNG bytes.
        pub(super) fn encode_png(self) -> Result<Vec<u8>, String> {
            let mut bytes = Vec::new();
            self.into_image()
                .write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
                .map_err(|e| e.to_string())?;
            Ok(bytes)
        }
    }
}

/// Checks that `value` can be placed on an axis.
fn check_value(what: impl FnOnce() -> String, value: f64) -> Result<f64> {
    if value.is_finite() && value.abs() <= MAX_VALUE {
        Ok(value)
    } else {
        Err(PlotError::BadValue { what: what(), value })
    }
}

/// An axis range covering `lo..=hi` with a margin of `pad` (a fraction of the span) on
/// each side; a zero span (one point, all-equal values) becomes a unit-wide range around
/// the value, so the axis never collapses.
fn padded(lo: f64, hi: f64, pad: f64) -> (f64, f64) {
    let span = hi - lo;
    if span > 0.0 {
        (lo - pad * span, hi + pad * span)
    } else {
        let half = (lo.abs() * 0.1).max(0.5);
        (lo - half, hi + half)
    }
}

/// Decades a log axis spans at most below its top: smaller values sit on its floor.
/// (plotters loops for ages over an axis whose ends' ratio overflows.)
const LOG_DECADES: f64 = 12.0;

/// The ends of a log axis for positive values from `positive_min` to `hi`, with room
/// `below` and `above` (factors), at most [`LOG_DECADES`] deep; `None` when no log axis
/// can show them (nothing positive, or only values too tiny to divide by).
fn log_range(positive_min: f64, hi: f64, below: f64, above: f64) -> Option<(f64, f64)> {
    if !(positive_min > 0.0 && positive_min.is_finite()) {
        return None;
    }
    let y1 = hi.max(positive_min) * above;
    let y0 = (positive_min / below).max(y1 / 10f64.powf(LOG_DECADES));
    (y0.is_normal() && (y1 / y0).is_finite()).then_some((y0, y1))
}

/// A number as an axis or bar label: integers plainly, others with up to three decimals,
/// very large or small magnitudes in scientific notation.
fn number_label(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".to_string()
    } else if !(1e-3..1e6).contains(&a) {
        let s = format!("{v:.2e}");
        // "1.50e6" reads better as "1.5e6".
        match s.split_once('e') {
            Some((m, e)) if m.contains('.') => format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.')),
            _ => s,
        }
    } else if v.fract() == 0.0 {
        format!("{v:.0}")
    } else {
        let digits = if a >= 100.0 {
            1
        } else if a >= 1.0 {
            2
        } else {
            3
        };
        let s = format!("{v:.digits$}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// The series colours, chosen to stay apart for colour-blind readers (Okabe-Ito).
const SERIES: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(230, 159, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(213, 94, 0),
    RGBColor(240, 228, 66),
    RGBColor(100, 100, 100),
];

/// The colour of the `i`-th series.
const fn series_colour(i: usize) -> RGBColor {
    SERIES[i % SERIES.len()]
}

/// Colour of reference marks (the paper's figures, the optimum).
const REFERENCE: RGBColor = RGBColor(200, 30, 30);

/// A filled diamond 14 pixels across, centred on its anchor: the mark of reference and
/// second values.
fn diamond(colour: RGBColor) -> Polygon<(i32, i32)> {
    Polygon::new(vec![(0, -7), (7, 0), (0, 7), (-7, 0)], colour.filled())
}

/// A categorical x axis: one position per name at `0, 1, ..`, spanning `-0.5..n - 0.5`,
/// with a tick and the name at each position.
struct Categories(Vec<String>);

impl Ranged for Categories {
    type FormatOption = plotters::coord::ranged1d::NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let fraction = (value + 0.5) / self.0.len().max(1) as f64;
        limit.0 + (fraction * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<Hint: plotters::coord::ranged1d::KeyPointHint>(&self, _hint: Hint) -> Vec<f64> {
        (0..self.0.len()).map(|i| i as f64).collect()
    }

    fn range(&self) -> std::ops::Range<f64> {
        -0.5..self.0.len() as f64 - 0.5
    }
}

impl plotters::coord::ranged1d::ValueFormatter<f64> for Categories {
    fn format_ext(&self, value: &f64) -> String {
        let i = value.round();
        if i >= 0.0 {
            self.0.get(i as usize).cloned().unwrap_or_default()
        } else {
            String::new()
        }
    }
}

/// Colour of body text (titles, notes).
const INK: RGBColor = RGBColor(30, 30, 30);

/// Font sizes in pixels.
const TITLE_PX: u32 = 26;
const LABEL_PX: u32 = 18;
const TICK_PX: u32 = 15;
const NOTE_PX: u32 = 15;

/// Splits `text` into lines no wider than `width` pixels at `px` pixels of the bundled
/// font (a word longer than a line gets a line of its own), honouring explicit newlines.
/// Blank text gives no lines.
fn wrap(text: &str, px: u32, width: u32) -> Result<Vec<String>> {
    register_font()?;
    let font = (FONT_FAMILY, px).into_font();
    let mut lines = Vec::new();
    for paragraph in text.lines() {
        let mut line = String::new();
        for word in paragraph.split_whitespace() {
            let candidate = if line.is_empty() {
                word.to_string()
            } else {
                format!("{line} {word}")
            };
            if line.is_empty() || font.box_size(&candidate).map_err(|_| PlotError::Font)?.0 <= width {
                line = candidate;
            } else {
                lines.push(std::mem::replace(&mut line, word.to_string()));
            }
        }
        lines.push(line);
    }
    while lines.last().is_some_and(String::is_empty) {
        lines.pop();
    }
    Ok(lines)
}

/// A mark in a legend, drawn before its text.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Mark {
    /// A line segment of this colour and width.
    Line(RGBColor, u32),
    /// A dashed line segment.
    Dashed(RGBColor),
    /// A filled square (a bar, a box) of this colour and opacity.
    Block(RGBColor, f64),
    /// A filled diamond (see [`diamond`]).
    Diamond(RGBColor),
    /// A black cross (a mean).
    Cross,
    /// A hollow circle (an outlier).
    Ring(RGBColor),
    /// A vertical bar with caps (an interval).
    Interval,
}

/// Width of a legend mark, and the gaps after a mark and after an entry, in pixels.
const MARK_W: i32 = 24;
const MARK_GAP: i32 = 8;
const ENTRY_GAP: i32 = 28;
/// Height of a legend row.
const LEGEND_ROW: u32 = 24;
/// Left edge of legends and notes, in line with the plot's y axis.
const INDENT: i32 = 90;

/// The parts of a chart around its plot: the title on top, a legend under it (one or more
/// rows of marks and their texts, laid out before drawing so the chart's height is
/// known), and a wrapped note at the bottom. Legends sit outside the plot, so they never
/// hide data.
struct Frame {
    title: String,
    /// Each legend entry with its row and x position.
    legend: Vec<(Mark, String, u32, i32)>,
    legend_rows: u32,
    note: Vec<String>,
}

impl Frame {
    /// Lays out `legend` and `note` for a chart `width` pixels wide.
    fn new(title: &str, legend: Vec<(Mark, String)>, note: &str, width: u32) -> Result<Frame> {
        register_font()?;
        let font = (FONT_FAMILY, TICK_PX).into_font();
        let (mut row, mut x) = (0, INDENT);
        let mut placed = Vec::new();
        for (mark, text) in legend {
            let w = MARK_W + MARK_GAP + font.box_size(&text).map_err(|_| PlotError::Font)?.0 as i32;
            if x > INDENT && x + w > width as i32 - 12 {
                (row, x) = (row + 1, INDENT);
            }
            placed.push((mark, text, row, x));
            x += w + ENTRY_GAP;
        }
        Ok(Frame {
            title: title.to_string(),
            legend_rows: placed.last().map_or(0, |p| p.2 + 1),
            legend: placed,
            note: wrap(note, NOTE_PX, width - 24)?,
        })
    }

    /// Height of the legend and the note: what the chart adds to its plot's height.
    fn extra_height(&self) -> u32 {
        let legend = if self.legend_rows == 0 {
            0
        } else {
            self.legend_rows * LEGEND_ROW + 6
        };
        let note = if self.note.is_empty() {
            0
        } else {
            self.note.len() as u32 * (NOTE_PX + 5) + 14
        };
        legend + note
    }

    /// Draws the title, legend and note on `root` and returns the area left for the plot.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DrawingArea<DB, Shift>, DB> {
        let area = if self.title.trim().is_empty() {
            root.margin(10, 0, 0, 0)
        } else {
            root.titled(&self.title, (FONT_FAMILY, TITLE_PX).into_font().color(&INK))?
        };
        let legend_h = if self.legend_rows == 0 {
            0
        } else {
            self.legend_rows * LEGEND_ROW + 6
        };
        let (legend, rest) = area.split_vertically(legend_h);
        for (mark, text, row, x) in &self.legend {
            let y = (row * LEGEND_ROW + LEGEND_ROW / 2) as i32;
            draw_mark(&legend, *mark, (x + MARK_W / 2, y))?;
            let style = TextStyle::from((FONT_FAMILY, TICK_PX).into_font())
                .color(&INK)
                .pos(Pos::new(HPos::Left, VPos::Center));
            legend.draw(&Text::new(text.as_str(), (x + MARK_W + MARK_GAP, y), style))?;
        }
        let note_h = self.extra_height() - legend_h;
        let (plot, note) = rest.split_vertically(rest.dim_in_pixel().1.saturating_sub(note_h));
        let style = (FONT_FAMILY, NOTE_PX).into_font().color(&INK);
        for (i, line) in self.note.iter().enumerate() {
            note.draw(&Text::new(
                line.as_str(),
                (12, 8 + i as i32 * (NOTE_PX as i32 + 5)),
                style.clone(),
            ))?;
        }
        Ok(plot)
    }
}

/// Draws `mark` centred on `centre` (pixels in `area`).
fn draw_mark<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, mark: Mark, centre: (i32, i32)) -> DrawResult<(), DB> {
    let (x, y) = centre;
    let half = MARK_W / 2;
    match mark {
        Mark::Line(colour, width) => area.draw(&PathElement::new(
            vec![(x - half, y), (x + half, y)],
            colour.stroke_width(width),
        )),
        Mark::Dashed(colour) => {
            area.draw(&PathElement::new(
                vec![(x - half, y), (x - 3, y)],
                colour.stroke_width(2),
            ))?;
            area.draw(&PathElement::new(
                vec![(x + 3, y), (x + half, y)],
                colour.stroke_width(2),
            ))
        }
        Mark::Block(colour, opacity) => area.draw(&Rectangle::new(
            [(x - 9, y - 7), (x + 9, y + 7)],
            colour.mix(opacity).filled(),
        )),
        Mark::Diamond(colour) => area.draw(&(EmptyElement::at(centre) + diamond(colour))),
        Mark::Cross => area.draw(&Cross::new(centre, 5, BLACK.stroke_width(2))),
        Mark::Ring(colour) => area.draw(&Circle::new(centre, 4, colour.stroke_width(2))),
        Mark::Interval => {
            area.draw(&PathElement::new(vec![(x, y - 7), (x, y + 7)], INK.stroke_width(2)))?;
            area.draw(&PathElement::new(
                vec![(x - 5, y - 7), (x + 5, y - 7)],
                INK.stroke_width(2),
            ))?;
            area.draw(&PathElement::new(
                vec![(x - 5, y + 7), (x + 5, y + 7)],
                INK.stroke_width(2),
            ))
        }
    }
}

/// Axis styling shared by every chart: tick labels and axis descriptions in the bundled
/// font, a light grid at the labelled ticks only.
fn style_mesh<X, Y, DB>(mesh: &mut plotters::chart::MeshStyle<'_, '_, X, Y, DB>)
where
    X: Ranged,
    Y: Ranged,
    DB: DrawingBackend,
{
    mesh.label_style((FONT_FAMILY, TICK_PX))
        .axis_desc_style((FONT_FAMILY, LABEL_PX))
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(220, 220, 220));
}

/// Each category's name as lines of tick text no wider than its share of `plot_width`
/// pixels, less a gap between neighbours (a word wider than that keeps a line of its own).
fn category_labels(names: &[String], plot_width: u32) -> Vec<Vec<String>> {
    let slot = (plot_width / names.len().max(1) as u32).saturating_sub(8).max(1);
    names
        .iter()
        .map(|n| wrap(n, TICK_PX, slot).unwrap_or_else(|_| vec![n.clone()]))
        .collect()
}

/// A chart with one category per name along x over the value axis `y`, its mesh drawn in
/// the house style with `y_label`: the frame bar charts and box plots share. Each name is
/// wrapped to its category's width (long names side by side once ran into one another),
/// and the label area grows to hold the most lines.
fn category_chart<'a, DB, Y>(
    area: &'a DrawingArea<DB, Shift>,
    names: Vec<String>,
    y: Y,
    y_label: &str,
) -> DrawResult<ChartContext<'a, DB, Cartesian2d<Categories, Y::CoordDescType>>, DB>
where
    DB: DrawingBackend,
    Y: plotters::coord::ranged1d::AsRangedCoord<Value = f64>,
    Y::CoordDescType: plotters::coord::ranged1d::ValueFormatter<f64>,
{
    const MARGIN_LEFT: u32 = 10;
    const MARGIN_RIGHT: u32 = 25;
    const Y_LABEL_AREA: u32 = 80;
    const LINE_PX: u32 = TICK_PX + 3;
    let plot_width = area
        .dim_in_pixel()
        .0
        .saturating_sub(MARGIN_LEFT + MARGIN_RIGHT + Y_LABEL_AREA);
    let labels = category_labels(&names, plot_width);
    let lines = labels.iter().map(Vec::len).max().unwrap_or(1).max(1) as u32;
    let mut chart = ChartBuilder::on(area)
        .margin_left(MARGIN_LEFT)
        .margin_right(MARGIN_RIGHT)
        .margin_top(10)
        .x_label_area_size(20 + lines * LINE_PX)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(Categories(names), y)?;
    let mut mesh = chart.configure_mesh();
    style_mesh(&mut mesh);
    mesh.disable_x_mesh()
        .x_label_formatter(&|_| String::new())
        .y_desc(y_label)
        .y_label_formatter(&|v| number_label(*v))
        .draw()?;
    let (xs, ys) = chart.plotting_area().get_pixel_range();
    let (base_x, base_y) = area.get_base_pixel();
    let style = TextStyle::from((FONT_FAMILY, TICK_PX).into_font())
        .color(&BLACK)
        .pos(Pos::new(HPos::Center, VPos::Top));
    let n = labels.len().max(1) as f64;
    for (i, lines) in labels.iter().enumerate() {
        let centre = xs.start + ((i as f64 + 0.5) / n * f64::from(xs.end - xs.start)).round() as i32;
        for (k, line) in lines.iter().enumerate() {
            let top = ys.end + 8 + k as i32 * LINE_PX as i32;
            area.draw_text(line, &style, (centre - base_x, top - base_y))?;
        }
    }
    Ok(chart)
}

#[cfg(test)]
mod test_support {
    //! Helpers shared by the plot tests.

    use std::path::{Path, PathBuf};

    /// A fresh, empty folder for one test's files, under the system temp folder; removed
    /// when dropped unless `BLOCKSTACK_KEEP_PLOTS` is set (to look at the pictures).
    pub(super) struct TempDir(PathBuf);

    impl std::ops::Deref for TempDir {
        type Target = Path;

        fn deref(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            if std::env::var_os("BLOCKSTACK_KEEP_PLOTS").is_none() {
                let _ = std::fs::remove_dir_all(&self.0);
            }
        }
    }

    /// A [`TempDir`] named after the process and `test`.
    pub(super) fn temp_dir(test: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("blockstack-plots-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        TempDir(dir)
    }

    /// Checks both chart files: the PNG decodes with the expected size and has dark
    /// (text) pixels in its top `title_rows` rows; the SVG is an `<svg>` document that
    /// contains `title`.
    pub(super) fn check_chart(files: &super::ChartFiles, size: (u32, u32), title: &str, title_rows: u32) {
        let png = image::open(&files.png).expect("PNG decodes").to_rgb8();
        assert_eq!(png.dimensions(), size);
        let dark = (0..title_rows.min(png.height()))
            .flat_map(|y| (0..png.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| png.get_pixel(x, y).0.iter().all(|&c| c < 100))
            .count();
        assert!(
            dark > 50,
            "the title region of {} has {dark} dark pixels",
            files.png.display()
        );
        check_svg(&files.svg, title);
    }

    /// Checks that `path` is an SVG document (opening and closing `svg` tags, as many
    /// `<text` openings as closings) containing `text`.
    pub(super) fn check_svg(path: &Path, text: &str) {
        let svg = std::fs::read_to_string(path).expect("SVG is UTF-8 text");
        assert!(
            svg.trim_start().starts_with("<svg"),
            "{} starts with {:?}",
            path.display(),
            &svg[..20]
        );
        assert!(svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("<text").count(), svg.matches("</text>").count());
        assert!(svg.contains(&escape(text)), "{} lacks {text:?}", path.display());
    }

    /// `text` with XML's special characters escaped, as plotters writes it.
    fn escape(text: &str) -> String {
        text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
    }

    /// The files in `dir`, sorted: no temporaries may be left behind.
    pub(super) fn listing(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .expect("dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn number_labels_are_short() {
        assert_eq!(number_label(0.0), "0");
        assert_eq!(number_label(12.0), "12");
        assert_eq!(number_label(12.5), "12.5");
        assert_eq!(number_label(10.16), "10.16");
        assert_eq!(number_label(123.45), "123.5");
        assert_eq!(number_label(0.25), "0.25");
        assert_eq!(number_label(1.5e6), "1.5e6");
        assert_eq!(number_label(-2e-5), "-2e-5");
    }

    #[test]
    fn padded_ranges_never_collapse() {
        assert_eq!(padded(0.0, 10.0, 0.1), (-1.0, 11.0));
        let (lo, hi) = padded(5.0, 5.0, 0.1);
        assert!(lo < 5.0 && hi > 5.0);
        let (lo, hi) = padded(MAX_VALUE, MAX_VALUE, 0.1);
        assert!(lo < hi && hi.is_finite());
        let (lo, hi) = padded(-MAX_VALUE, MAX_VALUE, 0.1);
        assert!(lo < hi && lo.is_finite() && hi.is_finite());
    }

    #[test]
    fn values_beyond_the_axis_limits_are_errors() {
        assert!(check_value(|| "x".into(), 1e15).is_ok());
        for bad in [f64::NAN, f64::INFINITY, -f64::INFINITY, 1e16, -1e300] {
            let err = check_value(|| "x".into(), bad).unwrap_err();
            assert!(matches!(err, PlotError::BadValue { .. }), "{bad}: {err}");
        }
    }

    #[test]
    fn long_category_names_wrap_within_their_share_of_the_axis() {
        // E6's eight arms on its chart's plot width ran into one another on one line.
        let names: Vec<String> = [
            "baseline, original",
            "demonstrator 1, original",
            "demonstrator 2, original",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let width = 3 * 90;
        let labels = category_labels(&names, width);
        let font = (FONT_FAMILY, TICK_PX).into_font();
        for (name, lines) in names.iter().zip(&labels) {
            assert!(lines.len() > 1, "{name:?} was not wrapped: {lines:?}");
            assert_eq!(lines.join(" "), *name);
            for line in lines {
                let single_word = !line.contains(' ');
                assert!(
                    single_word || font.box_size(line).unwrap().0 <= 90 - 8,
                    "{line:?} is wider than its slot"
                );
            }
        }
        assert_eq!(
            category_labels(&names, 3000),
            names.iter().map(|n| vec![n.clone()]).collect::<Vec<_>>()
        );
    }

    #[test]
    fn stems_keep_their_dots() {
        assert_eq!(
            with_extension(Path::new("out/e5.goal-1.0.2"), "png"),
            PathBuf::from("out/e5.goal-1.0.2.png")
        );
    }

    #[test]
    fn axes_survive_the_tiniest_values() {
        let dir = test_support::temp_dir("tiny");
        let tinies = [f64::from_bits(1), f64::MIN_POSITIVE, 1e-300, 1e-13];
        for (tiny, log_scale) in tinies.into_iter().flat_map(|t| [(t, true), (t, false)]) {
            for samples in [vec![tiny, 1.0, 1e15], vec![tiny, 2.0 * tiny], vec![tiny]] {
                let boxes = BoxPlot {
                    title: "tiny".into(),
                    y_label: "steps".into(),
                    arms: vec![Arm {
                        name: "a".into(),
                        steps: samples.clone(),
                        reference: None,
                    }],
                    reference_label: String::new(),
                    log_scale,
                    note: String::new(),
                };
                box_plot(&boxes, &dir.join("boxes")).expect("box plot");
                let bars = BarChart {
                    title: "tiny".into(),
                    y_label: "steps".into(),
                    bars: samples
                        .iter()
                        .map(|&v| Bar {
                            name: "a".into(),
                            value: v,
                            interval: None,
                            second: None,
                        })
                        .collect(),
                    value_label: String::new(),
                    interval_label: String::new(),
                    second_label: String::new(),
                    reference: None,
                    log_scale,
                    note: String::new(),
                };
                bar_chart(&bars, &dir.join("bars")).expect("bar chart");
                let curve = LearningCurve {
                    title: "tiny".into(),
                    steps_label: "steps".into(),
                    series: vec![LearningSeries {
                        name: "a".into(),
                        style: SeriesStyle::Line,
                        colour: 0,
                        points: samples
                            .iter()
                            .enumerate()
                            .map(|(i, &v)| LearningPoint {
                                games: i as u64,
                                failure_rate: 0.0,
                                failure_range: None,
                                mean_steps: Some(v),
                                steps_range: Some((v, v)),
                            })
                            .collect(),
                    }],
                    note: String::new(),
                };
                learning_curve(&curve, &dir.join("curve")).expect("learning curve");
            }
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config { cases: 24, ..Default::default() })]

        /// Any values at all (NaN, infinities, subnormals, huge, negative, empty lists):
        /// each chart is drawn or refused with an error, never a panic.
        #[test]
        fn no_values_make_a_chart_panic(
            values in proptest::collection::vec(proptest::num::f64::ANY, 0..12),
            log_scale in proptest::bool::ANY,
        ) {
            let dir = test_support::temp_dir("proptest");
            let arms = values
                .chunks(4)
                .enumerate()
                .map(|(i, c)| Arm { name: format!("arm {i}"), steps: c.to_vec(), reference: c.first().copied() })
                .collect();
            let boxes = BoxPlot {
                title: "any".into(),
                y_label: "steps".into(),
                arms,
                reference_label: "reference".into(),
                log_scale,
                note: String::new(),
            };
            let _ = box_plot(&boxes, &dir.join("boxes"));
            let bars = BarChart {
                title: "any".into(),
                y_label: "steps".into(),
                bars: values
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| Bar { name: i.to_string(), value: v, interval: Some((v, v.abs())), second: Some(-v) })
                    .collect(),
                value_label: "value".into(),
                interval_label: "interval".into(),
                second_label: "second".into(),
                reference: values.last().map(|&v| Reference { label: "ref".into(), value: v }),
                log_scale,
                note: String::new(),
            };
            let _ = bar_chart(&bars, &dir.join("bars"));
            let series = |style, shift: f64| LearningSeries {
                name: format!("{style:?}"),
                style,
                colour: 1,
                points: values
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| LearningPoint {
                        games: i as u64 * 100,
                        failure_rate: v / 1e3,
                        failure_range: Some((v / 1e3, shift)),
                        mean_steps: Some(v + shift),
                        steps_range: Some((v, -v)),
                    })
                    .collect(),
            };
            let curve = LearningCurve {
                title: "any".into(),
                steps_label: "steps".into(),
                series: vec![series(SeriesStyle::Line, 0.5), series(SeriesStyle::Diamonds, -1.0)],
                note: String::new(),
            };
            let _ = learning_curve(&curve, &dir.join("curve"));
        }
    }

    #[test]
    fn the_bundled_font_registers() {
        register_font().expect("font");
        register_font().expect("registering twice is harmless");
    }
}
