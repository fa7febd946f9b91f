//! Box plots of steps per arm (experiments E5 and E6).

use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{
    Chart, ChartFiles, FONT_FAMILY, Frame, INK, Mark, PlotError, REFERENCE, Result, TICK_PX, category_chart,
    check_value, diamond, series_colour, write_chart,
};

/// One arm of a comparison: a named sample of per-episode step counts.
#[derive(Clone, Debug, PartialEq)]
pub struct Arm {
    /// The arm's name, written under its box.
    pub name: String,
    /// Steps per episode. How failures count is the caller's choice (e.g. at the horizon).
    /// An empty sample draws "no data" in place of a box.
    pub steps: Vec<f64>,
    /// A reference value for this arm (e.g. the paper's mean), drawn as a red diamond.
    pub reference: Option<f64>,
}

/// A box plot to draw: one box per arm.
#[derive(Clone, Debug, PartialEq)]
pub struct BoxPlot {
    /// The chart's title.
    pub title: String,
    /// The y axis' description, e.g. "steps to goal (failures at 1000)".
    pub y_label: String,
    /// The arms, drawn left to right.
    pub arms: Vec<Arm>,
    /// The legend's name for the reference diamonds, e.g. "paper's mean".
    pub reference_label: String,
    /// A logarithmic y axis, for samples spanning orders of magnitude (successes near 20,
    /// failures at 1000). It reaches at most 12 decades below the largest value; values
    /// below its floor (zero, negatives) are drawn on the floor. With no positive value
    /// the axis stays linear.
    pub log_scale: bool,
    /// Text drawn under the chart, wrapped to its width; empty for none.
    pub note: String,
}

/// The five numbers of a Tukey box, plus what lies beyond the whiskers.
#[derive(Clone, Debug, PartialEq)]
struct Tukey {
    /// Lower whisker: the smallest value at or above `q1 - 1.5 IQR`.
    low: f64,
    q1: f64,
    median: f64,
    q3: f64,
    /// Upper whisker: the largest value at or below `q3 + 1.5 IQR`.
    high: f64,
    mean: f64,
    /// Values beyond the whiskers, each distinct value once with its count.
    outliers: Vec<(f64, usize)>,
}

impl Tukey {
    /// The box of a non-empty, finite sample; quartiles interpolated linearly between
    /// order statistics (NumPy's default, R's type 7).
    fn of(sample: &[f64]) -> Option<Tukey> {
        let mut s = sample.to_vec();
        s.sort_by(f64::total_cmp);
        let n = s.len();
        if n == 0 {
            return None;
        }
        let quantile = |q: f64| {
            let pos = q * (n - 1) as f64;
            let i = pos.floor() as usize;
            let frac = pos - i as f64;
            match s.get(i + 1) {
                Some(&next) if frac > 0.0 => s[i] + frac * (next - s[i]),
                _ => s[i],
            }
        };
        let (q1, median, q3) = (quantile(0.25), quantile(0.5), quantile(0.75));
        let iqr = q3 - q1;
        let (fence_lo, fence_hi) = (q1 - 1.5 * iqr, q3 + 1.5 * iqr);
        let inside = || s.iter().copied().filter(|&v| v >= fence_lo && v <= fence_hi);
        let low = inside().next().unwrap_or(q1);
        let high = inside().next_back().unwrap_or(q3);
        let mut outliers: Vec<(f64, usize)> = Vec::new();
        for v in s.iter().copied().filter(|&v| v < fence_lo || v > fence_hi) {
            match outliers.last_mut() {
                Some((last, count)) if *last == v => *count += 1,
                _ => outliers.push((v, 1)),
            }
        }
        let mean = s.iter().sum::<f64>() / n as f64;
        Some(Tukey {
            low,
            q1,
            median,
            q3,
            high,
            mean,
            outliers,
        })
    }
}

/// Draws `plot`: per arm a box from the first to the third quartile in the arm's colour,
/// a thick median line, whiskers to the furthest values within 1.5 IQR of the box, each
/// distinct outlier as a hollow dot (with "n×" beside it when it occurs n > 1 times), the
/// sample mean as a black cross, and the arm's reference as a red diamond; a legend
/// under the title explains the marks present. Writes `<stem>.png` and `<stem>.svg`.
///
/// Errors: no arms, every arm empty, or a value that is not finite or beyond
/// [`super::MAX_VALUE`].
pub fn box_plot(plot: &BoxPlot, stem: &Path) -> Result<ChartFiles> {
    if plot.arms.is_empty() {
        return Err(PlotError::Empty { what: "arms".into() });
    }
    if plot.arms.iter().all(|a| a.steps.is_empty()) {
        return Err(PlotError::Empty {
            what: "every arm's sample".into(),
        });
    }
    for arm in &plot.arms {
        for &v in &arm.steps {
            check_value(|| format!("a step count of arm {:?}", arm.name), v)?;
        }
        if let Some(r) = arm.reference {
            check_value(|| format!("the reference of arm {:?}", arm.name), r)?;
        }
    }
    let boxes: Vec<Option<Tukey>> = plot.arms.iter().map(|a| Tukey::of(&a.steps)).collect();
    let mut legend = vec![
        (Mark::Block(series_colour(0), 0.35), "quartiles".to_string()),
        (Mark::Line(BLACK, 3), "median".to_string()),
        (
            Mark::Line(INK, 2),
            "whiskers: furthest values within 1.5 IQR".to_string(),
        ),
        (Mark::Cross, "mean".to_string()),
    ];
    if boxes.iter().flatten().any(|b| !b.outliers.is_empty()) {
        legend.push((Mark::Ring(INK), "outliers".to_string()));
    }
    if plot.arms.iter().any(|a| a.reference.is_some()) {
        legend.push((Mark::Diamond(REFERENCE), plot.reference_label.clone()));
    }
    let width = 960.max(130 * plot.arms.len() as u32 + 200);
    let chart = BoxChart {
        plot,
        boxes,
        frame: Frame::new(&plot.title, legend, &plot.note, width)?,
        width,
    };
    write_chart(&chart, stem)
}

/// A validated box plot with its boxes computed and its frame laid out.
struct BoxChart<'a> {
    plot: &'a BoxPlot,
    boxes: Vec<Option<Tukey>>,
    frame: Frame,
    width: u32,
}

impl Chart for BoxChart<'_> {
    fn size(&self) -> (u32, u32) {
        (self.width, 600 + self.frame.extra_height())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<(), DB> {
        let values = || {
            self.plot
                .arms
                .iter()
                .flat_map(|a| a.steps.iter().chain(a.reference.iter()))
                .copied()
        };
        let (lo, hi) = values().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
        let positive_min = values().filter(|&v| v > 0.0).fold(f64::INFINITY, f64::min);
        if let Some((y0, y1)) = super::log_range(positive_min, hi, 1.5, 1.5).filter(|_| self.plot.log_scale) {
            self.draw_on(root, (y0..y1).log_scale(), y0)
        } else {
            let (y0, y1) = if lo >= 0.0 {
                (0.0, super::padded(0.0, hi, 0.05).1)
            } else {
                super::padded(lo, hi, 0.05)
            };
            self.draw_on(root, y0..y1, y0)
        }
    }
}

impl BoxChart<'_> {
    /// Draws the chart over the y axis `y`, whose lowest value is `floor` (where values
    /// a log axis cannot show are drawn).
    fn draw_on<DB: DrawingBackend, Y>(&self, root: &DrawingArea<DB, Shift>, y: Y, floor: f64) -> DrawResult<(), DB>
    where
        Y: AsRangedCoord<Value = f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let log = self.plot.log_scale && floor > 0.0;
        let at = |v: f64| if log { v.max(floor) } else { v };
        let plot_area = self.frame.draw(root)?;
        let names = self.plot.arms.iter().map(|a| a.name.clone()).collect();
        let mut chart = category_chart(&plot_area, names, y, &self.plot.y_label)?;

        let boxes = || {
            self.boxes
                .iter()
                .enumerate()
                .filter_map(|(i, b)| b.as_ref().map(|b| (i as f64, i, b)))
        };
        let half = 0.3;
        let cap = half / 2.5;
        for (x, i, b) in boxes() {
            let colour = series_colour(i);
            let (q1, q3) = ((x - half, at(b.q1)), (x + half, at(b.q3)));
            chart
                .plotting_area()
                .draw(&Rectangle::new([q1, q3], colour.mix(0.35).filled()))?;
            chart
                .plotting_area()
                .draw(&Rectangle::new([q1, q3], colour.stroke_width(2)))?;
            chart.draw_series([
                PathElement::new(vec![(x, at(b.q3)), (x, at(b.high))], INK.stroke_width(1)),
                PathElement::new(vec![(x, at(b.q1)), (x, at(b.low))], INK.stroke_width(1)),
                PathElement::new(vec![(x - cap, at(b.high)), (x + cap, at(b.high))], INK.stroke_width(2)),
                PathElement::new(vec![(x - cap, at(b.low)), (x + cap, at(b.low))], INK.stroke_width(2)),
                PathElement::new(
                    vec![(x - half, at(b.median)), (x + half, at(b.median))],
                    BLACK.stroke_width(3),
                ),
            ])?;
            chart
                .plotting_area()
                .draw(&Cross::new((x, at(b.mean)), 5, BLACK.stroke_width(2)))?;
            let beside = TextStyle::from((FONT_FAMILY, TICK_PX - 2).into_font())
                .color(&INK)
                .pos(Pos::new(HPos::Left, VPos::Center));
            for &(v, count) in &b.outliers {
                let dot = EmptyElement::at((x, at(v))) + Circle::new((0, 0), 4, colour.stroke_width(2));
                if count > 1 {
                    chart
                        .plotting_area()
                        .draw(&(dot + Text::new(format!("{count}×"), (8, 0), beside.clone())))?;
                } else {
                    chart.plotting_area().draw(&dot)?;
                }
            }
        }
        for (i, arm) in self.plot.arms.iter().enumerate() {
            if let Some(r) = arm.reference {
                chart
                    .plotting_area()
                    .draw(&(EmptyElement::at((i as f64, at(r))) + diamond(REFERENCE)))?;
            }
        }
        let y_range = chart.y_range();
        let mid = if log {
            (y_range.start * y_range.end).sqrt()
        } else {
            (y_range.start + y_range.end) / 2.0
        };
        let centred = TextStyle::from((FONT_FAMILY, TICK_PX).into_font())
            .color(&INK)
            .pos(Pos::new(HPos::Center, VPos::Center));
        for (i, _) in self.boxes.iter().enumerate().filter(|(_, b)| b.is_none()) {
            chart
                .plotting_area()
                .draw(&Text::new("no data", (i as f64, mid), centred.clone()))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{check_chart, listing, temp_dir};
    use super::*;

    fn plot(arms: Vec<Arm>) -> BoxPlot {
        BoxPlot {
            title: "E5 steps to goal per arm".into(),
            y_label: "steps to goal (failures at 1000)".into(),
            arms,
            reference_label: "paper's mean".into(),
            log_scale: false,
            note: "500 episodes per arm, same seeded starts.".into(),
        }
    }

    fn arm(name: &str, steps: Vec<f64>, reference: Option<f64>) -> Arm {
        Arm {
            name: name.into(),
            steps,
            reference,
        }
    }

    fn typical() -> Vec<Arm> {
        let spread = |base: f64, k: u32| {
            (0..200)
                .map(move |i| base + f64::from((i * k) % 37))
                .collect::<Vec<_>>()
        };
        let mut with_failures = spread(20.0, 7);
        with_failures.extend([1000.0; 5]);
        vec![
            arm("paper reward", spread(30.0, 11), Some(42.0)),
            arm("dense reward", with_failures, Some(25.0)),
            arm("step cost", spread(12.0, 3), None),
        ]
    }

    #[test]
    fn tukey_boxes_match_numpy() {
        // numpy.percentile([1, 2, 3, 4, 100], [25, 50, 75]) = [2, 3, 4]; fences -1 and 7.
        let t = Tukey::of(&[4.0, 2.0, 100.0, 1.0, 3.0]).expect("box");
        assert_eq!((t.q1, t.median, t.q3), (2.0, 3.0, 4.0));
        assert_eq!((t.low, t.high), (1.0, 4.0));
        assert_eq!(t.outliers, [(100.0, 1)]);
        assert_eq!(t.mean, 22.0);
        // numpy.percentile([1, 2, 3, 4], [25, 50, 75]) = [1.75, 2.5, 3.25].
        let t = Tukey::of(&[1.0, 2.0, 3.0, 4.0]).expect("box");
        assert_eq!((t.q1, t.median, t.q3), (1.75, 2.5, 3.25));
        assert_eq!((t.low, t.high), (1.0, 4.0));
        let t = Tukey::of(&[7.0]).expect("box");
        assert_eq!((t.low, t.q1, t.median, t.q3, t.high), (7.0, 7.0, 7.0, 7.0, 7.0));
        assert!(t.outliers.is_empty());
        // Repeated outliers are drawn once, with their count.
        let mut s = vec![10.0; 40];
        s.extend([1000.0; 5]);
        s.extend([11.0; 40]);
        let t = Tukey::of(&s).expect("box");
        assert_eq!(t.outliers, [(1000.0, 5)]);
        assert_eq!(Tukey::of(&[]), None);
    }

    #[test]
    fn writes_png_and_svg_with_legend_and_names() {
        let dir = temp_dir("boxes");
        let p = plot(typical());
        let files = box_plot(&p, &dir.join("e5")).expect("drawn");
        let size = image::open(&files.png).expect("png").to_rgb8().dimensions();
        check_chart(&files, size, &p.title, 40);
        let svg = std::fs::read_to_string(&files.svg).expect("svg");
        for text in [
            "paper reward",
            "step cost",
            "s mean",
            "outliers",
            "median",
            "failures at 1000",
            "5×",
        ] {
            assert!(svg.contains(text), "svg lacks {text:?}");
        }
        let mut log = plot(typical());
        log.log_scale = true;
        let files = box_plot(&log, &dir.join("e5-log")).expect("drawn");
        check_chart(&files, size, &log.title, 40);
        assert_eq!(listing(&dir), ["e5-log.png", "e5-log.svg", "e5.png", "e5.svg"]);
    }

    #[test]
    fn odd_but_valid_samples_still_draw() {
        let dir = temp_dir("boxes-odd");
        let cases = [
            ("single", vec![arm("one", vec![5.0], None)]),
            (
                "equal",
                vec![arm("a", vec![3.0; 50], Some(3.0)), arm("b", vec![3.0; 5], None)],
            ),
            ("zeros", vec![arm("a", vec![0.0; 10], None)]),
            (
                "one-empty",
                vec![arm("a", vec![], Some(4.0)), arm("b", vec![1.0, 2.0], None)],
            ),
            ("negative", vec![arm("a", vec![-5.0, 2.0, 1e15], None)]),
            ("huge", vec![arm("a", vec![1e15, 1e15 - 1.0], Some(-1e15))]),
            (
                "many",
                (0..12)
                    .map(|i| arm(&format!("arm {i}"), vec![f64::from(i); 3], None))
                    .collect(),
            ),
        ];
        for (name, arms) in cases {
            for log_scale in [false, true] {
                let mut p = plot(arms.clone());
                p.log_scale = log_scale;
                p.note = String::new();
                let stem = dir.join(format!("{name}-{log_scale}"));
                let files = box_plot(&p, &stem).unwrap_or_else(|e| panic!("{name}: {e}"));
                let size = image::open(&files.png).expect("png").to_rgb8().dimensions();
                check_chart(&files, size, &p.title, 40);
            }
        }
    }

    #[test]
    fn bad_samples_are_errors() {
        let dir = temp_dir("boxes-bad");
        let stem = dir.join("bad");
        assert!(matches!(box_plot(&plot(vec![]), &stem), Err(PlotError::Empty { .. })));
        assert!(matches!(
            box_plot(&plot(vec![arm("a", vec![], None)]), &stem),
            Err(PlotError::Empty { .. })
        ));
        for bad in [f64::NAN, f64::NEG_INFINITY, 2e15] {
            let err = box_plot(&plot(vec![arm("a", vec![1.0, bad], None)]), &stem).unwrap_err();
            assert!(err.to_string().contains("arm \"a\""), "{err}");
            let err = box_plot(&plot(vec![arm("a", vec![1.0], Some(bad))]), &stem).unwrap_err();
            assert!(matches!(err, PlotError::BadValue { .. }), "{err}");
        }
        assert!(listing(&dir).is_empty());
    }
}
