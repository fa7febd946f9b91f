//! The learning curves of experiment E4: how learners' test results improve with training,
//! ours beside the paper's published values (its Fig. 3).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{
    Chart, ChartFiles, FONT_FAMILY, Frame, LABEL_PX, Mark, PlotError, Result, check_value, diamond, number_label,
    series_colour, style_mesh, write_chart,
};

/// One point of a learning curve: the test results after some amount of training.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LearningPoint {
    /// Training games played before the test.
    pub games: u64,
    /// The share of test games that missed the goal within the horizon, in `[0, 1]`.
    pub failure_rate: f64,
    /// The range of that share over replicates (drawn as a bar), if shown.
    pub failure_range: Option<(f64, f64)>,
    /// Mean steps (as [`LearningCurve::steps_label`] says); `None` when there is none (drawn
    /// as a gap in the line).
    pub mean_steps: Option<f64>,
    /// The range of the mean over replicates (drawn as a bar), if shown.
    pub steps_range: Option<(f64, f64)>,
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeriesStyle {
    /// Measured: a line with dots, and the ranges as bars.
    Line,
    /// Reference values (the paper's): diamonds, no line.
    Diamonds,
}

/// One learner's points, or the paper's values for comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct LearningSeries {
    /// The name in the legend.
    pub name: String,
    /// How it is drawn.
    pub style: SeriesStyle,
    /// Its colour: an index into the palette (a measured series and the reference values it
    /// is compared with share one).
    pub colour: usize,
    /// The points, in any order (they are drawn sorted by games).
    pub points: Vec<LearningPoint>,
}

/// Learning curves to draw: failures and mean steps against training games.
#[derive(Clone, Debug, PartialEq)]
pub struct LearningCurve {
    /// The chart's title.
    pub title: String,
    /// What the lower panel's means are, e.g. "mean steps to goal over successful games".
    pub steps_label: String,
    /// The series; at least one point in all.
    pub series: Vec<LearningSeries>,
    /// Text drawn under the panels, wrapped to the chart's width; empty for none.
    pub note: String,
}

/// Chart size in pixels, before the legend and the note.
const WIDTH: u32 = 960;
const PANELS_HEIGHT: u32 = 720;

/// Draws `curve` as two panels over the same x axis (training games): the share of test
/// games failed on top, mean steps below; measured series as lines with dots and range
/// bars, reference values as diamonds; the title and a legend above, the note below.
/// Writes `<stem>.png` and `<stem>.svg`.
///
/// Errors: no points, a failure share outside `[0, 1]`, a mean that is negative, not
/// finite or beyond [`super::MAX_VALUE`], or a range whose low end is above its high end.
pub fn learning_curve(curve: &LearningCurve, stem: &Path) -> Result<ChartFiles> {
    if curve.series.iter().all(|s| s.points.is_empty()) {
        return Err(PlotError::Empty { what: "points".into() });
    }
    let mut series = curve.series.clone();
    for s in &mut series {
        s.points.sort_by_key(|p| p.games);
        for p in &s.points {
            check_point(&s.name, p)?;
        }
    }
    let mut legend: Vec<(Mark, String)> = series
        .iter()
        .map(|s| {
            let colour = series_colour(s.colour);
            let mark = match s.style {
                SeriesStyle::Line => Mark::Line(colour, 2),
                SeriesStyle::Diamonds => Mark::Diamond(colour),
            };
            (mark, s.name.clone())
        })
        .collect();
    if series
        .iter()
        .flat_map(|s| &s.points)
        .any(|p| p.failure_range.is_some() || p.steps_range.is_some())
    {
        legend.push((Mark::Interval, "range over replicates".into()));
    }
    let frame = Frame::new(&curve.title, legend, &curve.note, WIDTH)?;
    write_chart(&LearningChart { curve, series, frame }, stem)
}

/// Checks that `p` of series `name` can be drawn.
fn check_point(name: &str, p: &LearningPoint) -> Result<()> {
    let what = |figure: &str| format!("{figure} of \"{name}\" at {} games", p.games);
    check_value(|| "the number of training games".into(), p.games as f64)?;
    let ranges = [
        (p.failure_rate, p.failure_range, "the failure share"),
        (p.mean_steps.unwrap_or(0.0), p.steps_range, "the mean steps"),
    ];
    for (value, range, figure) in ranges {
        check_value(|| what(figure), value)?;
        if let Some((lo, hi)) = range {
            check_value(|| what(figure), lo)?;
            check_value(|| what(figure), hi)?;
            if lo > hi {
                return Err(PlotError::Inconsistent {
                    what: what(figure),
                    reason: format!("its range runs from {lo} down to {hi}"),
                });
            }
        }
    }
    if !(0.0..=1.0).contains(&p.failure_rate) {
        return Err(PlotError::Inconsistent {
            what: what("the failure share"),
            reason: format!("{} is not a share of games (0 to 1)", p.failure_rate),
        });
    }
    if p.mean_steps.is_some_and(|m| m < 0.0) {
        return Err(PlotError::Inconsistent {
            what: what("the mean steps"),
            reason: "a mean number of steps is never negative".into(),
        });
    }
    Ok(())
}

/// A validated chart: sorted series, with its title, legend and note laid out.
struct LearningChart<'a> {
    curve: &'a LearningCurve,
    series: Vec<LearningSeries>,
    frame: Frame,
}

/// One panel's data for one series: its runs of points (a line breaks where a value is
/// missing), its range bars, and how it is drawn.
struct PanelSeries {
    runs: Vec<Vec<(f64, f64)>>,
    bars: Vec<(f64, f64, f64)>,
    style: SeriesStyle,
    colour: RGBColor,
}

impl LearningChart<'_> {
    /// Every series' data for a panel showing `value` (with its range).
    fn panel_series(&self, value: impl Fn(&LearningPoint) -> Option<(f64, Option<(f64, f64)>)>) -> Vec<PanelSeries> {
        self.series
            .iter()
            .map(|s| {
                let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
                let mut bars = Vec::new();
                for p in &s.points {
                    let x = p.games as f64;
                    match value(p) {
                        Some((v, range)) => {
                            runs.last_mut().expect("never empty").push((x, v));
                            bars.extend(range.map(|(lo, hi)| (x, lo, hi)));
                        }
                        None if runs.last().is_some_and(|r| !r.is_empty()) => runs.push(Vec::new()),
                        None => {}
                    }
                }
                runs.retain(|r| !r.is_empty());
                PanelSeries {
                    runs,
                    bars,
                    style: s.style,
                    colour: series_colour(s.colour),
                }
            })
            .collect()
    }
}

impl Chart for LearningChart<'_> {
    fn size(&self) -> (u32, u32) {
        (WIDTH, PANELS_HEIGHT + self.frame.extra_height())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<(), DB> {
        let panels = self.frame.draw(root)?;
        let (top, bottom) = panels.split_vertically(panels.dim_in_pixel().1 / 2);

        let games = || self.series.iter().flat_map(|s| &s.points).map(|p| p.games as f64);
        let max_games = games().fold(0.0, f64::max);
        let min_games = games().fold(f64::INFINITY, f64::min);
        // Training starts at zero games: keep zero on the axis unless the points are all
        // far from it, and pad a single point.
        let (x0, x1) = if max_games > 0.0 && min_games <= 0.5 * max_games {
            (0.0, max_games * 1.03)
        } else {
            super::padded(min_games, max_games, 0.05)
        };

        let failures = self.panel_series(|p| {
            Some((
                100.0 * p.failure_rate,
                p.failure_range.map(|(lo, hi)| (100.0 * lo, 100.0 * hi)),
            ))
        });
        panel(&top, (x0, x1), (0.0, 108.0), "failures, % of test games", &failures)?;

        let steps = self.panel_series(|p| p.mean_steps.map(|m| (m, p.steps_range)));
        let highest = steps
            .iter()
            .flat_map(|s| {
                s.runs
                    .iter()
                    .flatten()
                    .map(|&(_, v)| v)
                    .chain(s.bars.iter().map(|b| b.2))
            })
            .fold(0.0, f64::max);
        let y1 = if highest > 0.0 { highest * 1.1 } else { 1.0 };
        panel(&bottom, (x0, x1), (0.0, y1), &self.curve.steps_label, &steps)?;
        if steps.iter().all(|s| s.runs.is_empty()) {
            let (w, h) = bottom.dim_in_pixel();
            let centred = TextStyle::from((FONT_FAMILY, LABEL_PX).into_font())
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Center));
            bottom.draw(&Text::new(
                "no successful test episode",
                (w as i32 / 2, h as i32 / 2),
                centred,
            ))?;
        }
        Ok(())
    }
}

/// One panel: axes over `x` and `y` described by `y_desc` on the left and "training
/// games" below, and each series drawn in its style.
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    x: (f64, f64),
    y: (f64, f64),
    y_desc: &str,
    series: &[PanelSeries],
) -> DrawResult<(), DB> {
    let mut chart = ChartBuilder::on(area)
        .margin_left(10)
        .margin_right(25)
        .margin_top(10)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)?;
    let mut mesh = chart.configure_mesh();
    style_mesh(&mut mesh);
    mesh.x_desc("training games")
        .y_desc(y_desc)
        .x_label_formatter(&|v| number_label(*v))
        .y_label_formatter(&|v| number_label(*v))
        .draw()?;
    for s in series {
        for &(x, lo, hi) in &s.bars {
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(x, lo), (x, hi)],
                s.colour.mix(0.6).stroke_width(2),
            )))?;
        }
        for run in &s.runs {
            match s.style {
                SeriesStyle::Line => {
                    chart.draw_series(LineSeries::new(run.iter().copied(), s.colour.stroke_width(2)))?;
                    chart.draw_series(run.iter().map(|&p| Circle::new(p, 4, s.colour.filled())))?;
                }
                SeriesStyle::Diamonds => {
                    chart.draw_series(run.iter().map(|&p| EmptyElement::at(p) + diamond(s.colour)))?;
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{check_chart, listing, temp_dir};
    use super::*;

    fn point(games: u64, failure_rate: f64, mean_steps: Option<f64>) -> LearningPoint {
        LearningPoint {
            games,
            failure_rate,
            failure_range: None,
            mean_steps,
            steps_range: None,
        }
    }

    fn curve(points: Vec<LearningPoint>) -> LearningCurve {
        LearningCurve {
            title: "E4 learning curve: goal 1,0,2".into(),
            steps_label: "mean steps to goal".into(),
            series: vec![LearningSeries {
                name: "ours".into(),
                style: SeriesStyle::Line,
                colour: 0,
                points,
            }],
            note: "Paper, Fig. 3: failures fall to zero within about 20,000 training games while mean steps \
                   fall from several hundred towards 20; our learner is shown for the same schedule."
                .into(),
        }
    }

    fn typical() -> Vec<LearningPoint> {
        (0..=10)
            .map(|i| LearningPoint {
                failure_range: Some((0.0, 1.0 - i as f64 / 10.0)),
                steps_range: (i > 0).then(|| (300.0 / i as f64, 500.0 / i as f64 + 20.0)),
                ..point(
                    i * 2000,
                    1.0 - i as f64 / 10.0,
                    (i > 0).then(|| 400.0 / i as f64 + 10.0),
                )
            })
            .collect()
    }

    /// Ours and the paper's values beside them, as E4 draws them.
    fn with_reference() -> LearningCurve {
        let mut c = curve(typical());
        c.series.push(LearningSeries {
            name: "paper, Fig. 3".into(),
            style: SeriesStyle::Diamonds,
            colour: 0,
            points: vec![point(5, 0.71, Some(840.0)), point(100, 0.3, Some(488.0))],
        });
        c
    }

    #[test]
    fn writes_png_and_svg_with_title_legend_and_note() {
        let dir = temp_dir("learning");
        let c = with_reference();
        let files = learning_curve(&c, &dir.join("e4")).expect("drawn");
        let png = image::open(&files.png).expect("png").to_rgb8();
        let size = png.dimensions();
        assert!(
            size.0 == WIDTH && size.1 > PANELS_HEIGHT,
            "{size:?}: the note adds height"
        );
        check_chart(&files, size, &c.title, 40);
        let svg = std::fs::read_to_string(&files.svg).expect("svg");
        for text in [
            "training games",
            "failures, % of test games",
            "mean steps to goal",
            "paper, Fig. 3",
            "range over replicates",
            "Paper, Fig. 3:",
        ] {
            assert!(svg.contains(text), "svg lacks {text:?}");
        }
        assert_eq!(listing(&dir), ["e4.png", "e4.svg"]);
    }

    #[test]
    fn odd_but_valid_curves_still_draw() {
        let dir = temp_dir("learning-odd");
        let single = vec![point(500, 0.03, Some(12.0))];
        let all_failed = vec![point(0, 1.0, None), point(10, 1.0, None)];
        let flat = (0..5).map(|_| point(7, 0.0, Some(5.0))).collect();
        let huge = vec![point(0, 0.0, Some(1e15)), point(1_000_000_000_000_000, 1.0, Some(0.0))];
        let gaps = vec![
            point(0, 0.5, Some(100.0)),
            point(1, 1.0, None),
            point(2, 0.4, Some(80.0)),
        ];
        for (name, points) in [
            ("single", single),
            ("all-failed", all_failed),
            ("flat", flat),
            ("huge", huge),
            ("gaps", gaps),
        ] {
            let mut c = curve(points);
            c.note = String::new();
            let files = learning_curve(&c, &dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
            let size = image::open(&files.png).expect("png").to_rgb8().dimensions();
            check_chart(&files, size, &c.title, 40);
        }
    }

    #[test]
    fn bad_curves_are_errors() {
        let dir = temp_dir("learning-bad");
        let stem = dir.join("bad");
        let err = learning_curve(&curve(Vec::new()), &stem).unwrap_err();
        assert!(matches!(err, PlotError::Empty { .. }), "{err}");
        let mut c = curve(typical());
        c.series[0].points[3].failure_rate = 1.01;
        let err = learning_curve(&c, &stem).unwrap_err();
        assert!(err.to_string().contains("1.01 is not a share of games"), "{err}");
        let mut c = curve(typical());
        c.series[0].points[3].failure_range = Some((0.5, 0.2));
        assert!(matches!(learning_curve(&c, &stem), Err(PlotError::Inconsistent { .. })));
        for bad in [f64::NAN, f64::INFINITY, 1e300, -1.0] {
            let mut c = curve(typical());
            c.series[0].points[2].mean_steps = Some(bad);
            assert!(learning_curve(&c, &stem).is_err(), "mean {bad}");
        }
        let mut c = curve(typical());
        c.series[0].points[2].mean_steps = Some(1e300);
        let err = learning_curve(&c, &stem).unwrap_err().to_string();
        assert!(
            err.starts_with("the mean steps of \"ours\" at 4000 games is 1e300, which cannot be plotted"),
            "{err}"
        );
        assert!(listing(&dir).is_empty(), "errors write nothing");
    }

    #[test]
    fn a_missing_folder_is_a_write_error() {
        let dir = temp_dir("learning-missing");
        let err = learning_curve(&curve(typical()), &dir.join("no/such/folder/e4")).unwrap_err();
        assert!(matches!(err, PlotError::Write(_)), "{err}");
    }
}
