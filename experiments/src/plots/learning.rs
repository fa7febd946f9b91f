//! The learning curve of experiment E4: how a learner's test results improve with training.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{
    Chart, ChartFiles, FONT_FAMILY, Frame, LABEL_PX, Mark, PlotError, Result, check_value, number_label, series_colour,
    style_mesh, write_chart,
};

/// One point of a learning curve: the test results after some amount of training.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LearningPoint {
    /// Training games played before the test.
    pub games: u64,
    /// Test episodes that missed the goal within the horizon, out of
    /// [`LearningCurve::test_episodes`].
    pub failures: usize,
    /// Mean steps to the goal over the successful test episodes; `None` when every test
    /// episode failed (drawn as a gap in the line).
    pub mean_steps: Option<f64>,
}

/// A learning curve to draw: failures and mean steps to goal against training games.
#[derive(Clone, Debug, PartialEq)]
pub struct LearningCurve {
    /// The chart's title.
    pub title: String,
    /// Test episodes behind each point (the failures' upper bound); at least 1.
    pub test_episodes: usize,
    /// The points, in any order (they are drawn sorted by games).
    pub points: Vec<LearningPoint>,
    /// Text drawn under the panels, wrapped to the chart's width (e.g. the trend of the
    /// paper's Fig. 3 for comparison); empty for none.
    pub note: String,
}

/// Chart size in pixels, before the legend and the note.
const WIDTH: u32 = 960;
const PANELS_HEIGHT: u32 = 720;

/// Draws `curve` as two panels over the same x axis (training games): failures on top,
/// mean steps to goal below, each a line with dots; the title and a legend above, the
/// note below. Writes `<stem>.png` and `<stem>.svg`.
///
/// Errors: no points, zero test episodes, more failures than test episodes, or a mean
/// that is negative, not finite or beyond [`super::MAX_VALUE`].
pub fn learning_curve(curve: &LearningCurve, stem: &Path) -> Result<ChartFiles> {
    if curve.points.is_empty() {
        return Err(PlotError::Empty { what: "points".into() });
    }
    if curve.test_episodes == 0 {
        return Err(PlotError::Inconsistent {
            what: "the learning curve".into(),
            reason: "there are no test episodes behind the points".into(),
        });
    }
    let mut points = curve.points.clone();
    points.sort_by_key(|p| p.games);
    for p in &points {
        check_value(|| "the number of training games".into(), p.games as f64)?;
        if p.failures > curve.test_episodes {
            return Err(PlotError::Inconsistent {
                what: format!("the point at {} games", p.games),
                reason: format!("{} failures out of {} test episodes", p.failures, curve.test_episodes),
            });
        }
        if let Some(m) = p.mean_steps {
            check_value(|| format!("the mean steps at {} games", p.games), m)?;
            if m < 0.0 {
                return Err(PlotError::Inconsistent {
                    what: format!("the point at {} games", p.games),
                    reason: format!("a negative mean of {m} steps"),
                });
            }
        }
    }
    let gaps = points.iter().any(|p| p.mean_steps.is_none());
    let legend = vec![
        (
            Mark::Line(FAILURES, 2),
            format!("failures out of {} test episodes", curve.test_episodes),
        ),
        (
            Mark::Line(STEPS, 2),
            if gaps {
                "mean steps to goal over successful episodes (gap: none succeeded)".to_string()
            } else {
                "mean steps to goal over successful episodes".to_string()
            },
        ),
    ];
    let frame = Frame::new(&curve.title, legend, &curve.note, WIDTH)?;
    write_chart(&LearningChart { curve, points, frame }, stem)
}

/// Colours of the two series.
const FAILURES: RGBColor = series_colour(5);
const STEPS: RGBColor = series_colour(0);

/// A validated curve, sorted, with its title, legend and note laid out.
struct LearningChart<'a> {
    curve: &'a LearningCurve,
    points: Vec<LearningPoint>,
    frame: Frame,
}

impl Chart for LearningChart<'_> {
    fn size(&self) -> (u32, u32) {
        (WIDTH, PANELS_HEIGHT + self.frame.extra_height())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<(), DB> {
        let panels = self.frame.draw(root)?;
        let (top, bottom) = panels.split_vertically(panels.dim_in_pixel().1 / 2);

        let max_games = self.points.last().map_or(0, |p| p.games) as f64;
        let min_games = self.points.first().map_or(0, |p| p.games) as f64;
        // Training starts at zero games: keep zero on the axis unless the points are all
        // far from it, and pad a single point.
        let (x0, x1) = if max_games > 0.0 && min_games <= 0.5 * max_games {
            (0.0, max_games * 1.03)
        } else {
            super::padded(min_games, max_games, 0.05)
        };

        let n = self.curve.test_episodes as f64;
        let failures: Vec<(f64, f64)> = self
            .points
            .iter()
            .map(|p| (p.games as f64, p.failures as f64))
            .collect();
        panel(
            &top,
            (x0, x1),
            (0.0, n * 1.08),
            &format!("failures (of {})", self.curve.test_episodes),
            &[failures],
            FAILURES,
        )?;

        // Mean steps: one line per run of points with a mean, broken where none exists.
        let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        for p in &self.points {
            match p.mean_steps {
                Some(m) => runs.last_mut().expect("never empty").push((p.games as f64, m)),
                None if runs.last().is_some_and(|r| !r.is_empty()) => runs.push(Vec::new()),
                None => {}
            }
        }
        runs.retain(|r| !r.is_empty());
        let max_mean = runs.iter().flatten().map(|&(_, m)| m).fold(0.0, f64::max);
        let y1 = if max_mean > 0.0 { max_mean * 1.1 } else { 1.0 };
        panel(&bottom, (x0, x1), (0.0, y1), "mean steps to goal", &runs, STEPS)?;
        if runs.is_empty() {
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
/// games" below, and the `runs` as lines with dots in `colour`.
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    x: (f64, f64),
    y: (f64, f64),
    y_desc: &str,
    runs: &[Vec<(f64, f64)>],
    colour: RGBColor,
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
    for run in runs {
        chart.draw_series(LineSeries::new(run.iter().copied(), colour.stroke_width(2)))?;
        chart.draw_series(run.iter().map(|&p| Circle::new(p, 4, colour.filled())))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{check_chart, listing, temp_dir};
    use super::*;

    fn curve(points: Vec<LearningPoint>) -> LearningCurve {
        LearningCurve {
            title: "E4 learning curve: goal 1,0,2".into(),
            test_episodes: 100,
            points,
            note: "Paper, Fig. 3: failures fall to zero within about 20,000 training games while mean steps \
                   fall from several hundred towards 20; our learner is shown for the same schedule."
                .into(),
        }
    }

    fn typical() -> Vec<LearningPoint> {
        (0..=10)
            .map(|i| LearningPoint {
                games: i * 2000,
                failures: (100 - i as usize * 10).min(100),
                mean_steps: (i > 0).then(|| 400.0 / i as f64 + 10.0),
            })
            .collect()
    }

    #[test]
    fn writes_png_and_svg_with_title_and_note() {
        let dir = temp_dir("learning");
        let c = curve(typical());
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
            "failures out of 100 test episodes",
            "mean steps to goal",
            "Paper, Fig. 3:",
        ] {
            assert!(svg.contains(text), "svg lacks {text:?}");
        }
        assert_eq!(listing(&dir), ["e4.png", "e4.svg"]);
    }

    #[test]
    fn odd_but_valid_curves_still_draw() {
        let dir = temp_dir("learning-odd");
        let single = vec![LearningPoint {
            games: 500,
            failures: 3,
            mean_steps: Some(12.0),
        }];
        let all_failed = vec![
            LearningPoint {
                games: 0,
                failures: 100,
                mean_steps: None,
            },
            LearningPoint {
                games: 10,
                failures: 100,
                mean_steps: None,
            },
        ];
        let flat = (0..5)
            .map(|_| LearningPoint {
                games: 7,
                failures: 0,
                mean_steps: Some(5.0),
            })
            .collect();
        let huge = vec![
            LearningPoint {
                games: 0,
                failures: 0,
                mean_steps: Some(1e15),
            },
            LearningPoint {
                games: 1_000_000_000_000_000,
                failures: 100,
                mean_steps: Some(0.0),
            },
        ];
        let gaps = vec![
            LearningPoint {
                games: 0,
                failures: 50,
                mean_steps: Some(100.0),
            },
            LearningPoint {
                games: 1,
                failures: 100,
                mean_steps: None,
            },
            LearningPoint {
                games: 2,
                failures: 40,
                mean_steps: Some(80.0),
            },
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
        c.test_episodes = 0;
        assert!(matches!(learning_curve(&c, &stem), Err(PlotError::Inconsistent { .. })));
        let mut c = curve(typical());
        c.points[3].failures = 101;
        let err = learning_curve(&c, &stem).unwrap_err();
        assert!(err.to_string().contains("101 failures out of 100"), "{err}");
        for bad in [f64::NAN, f64::INFINITY, 1e300, -1.0] {
            let mut c = curve(typical());
            c.points[2].mean_steps = Some(bad);
            assert!(learning_curve(&c, &stem).is_err(), "mean {bad}");
        }
        let mut c = curve(typical());
        c.points[2].mean_steps = Some(1e300);
        let err = learning_curve(&c, &stem).unwrap_err().to_string();
        assert!(
            err.starts_with("the mean steps at 4000 games is 1e300, which cannot be plotted"),
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
