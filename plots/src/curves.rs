//! Learning curves of several learners on one chart: a line per learner of a test figure
//! (say, the share of test games that reached the goal) against training (E8).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    Chart, ChartFiles, Frame, Mark, PlotError, Result, check_value, number_label, series_colour, style_mesh,
    write_chart,
};

/// One learner's curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// The learner, in the legend.
    pub name: String,
    /// `(training, value)` points, in any order (drawn sorted by training).
    pub points: Vec<(f64, f64)>,
}

/// Several learning curves over the same axes.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvesChart {
    /// The chart's title.
    pub title: String,
    /// What x counts, e.g. "gradient steps".
    pub x_label: String,
    /// What y is, e.g. "reached the goal (%)".
    pub y_label: String,
    /// The y axis's range; `None` fits the data.
    pub y_range: Option<(f64, f64)>,
    /// The curves, one colour each, in legend order.
    pub series: Vec<Series>,
    /// Text under the chart; empty for none.
    pub note: String,
}

const WIDTH: u32 = 960;
const PLOT_HEIGHT: u32 = 520;

/// Draws `chart` (each series a line with dots) to `<stem>.png` and `<stem>.svg`.
///
/// Errors: no series, a series without points, a value not finite or beyond
/// [`super::MAX_VALUE`], or a y range whose low end is not below its high end.
pub fn curves_chart(chart: &CurvesChart, stem: &Path) -> Result<ChartFiles> {
    if chart.series.is_empty() {
        return Err(PlotError::Empty { what: "series".into() });
    }
    let mut series = chart.series.clone();
    for s in &mut series {
        if s.points.is_empty() {
            return Err(PlotError::Empty {
                what: format!("the points of {:?}", s.name),
            });
        }
        for &(x, y) in &s.points {
            check_value(|| format!("a training value of {:?}", s.name), x)?;
            check_value(|| format!("a value of {:?}", s.name), y)?;
        }
        s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    if let Some((lo, hi)) = chart.y_range {
        check_value(|| "the low end of the y range".into(), lo)?;
        check_value(|| "the high end of the y range".into(), hi)?;
        if lo >= hi {
            return Err(PlotError::Inconsistent {
                what: "the y range".into(),
                reason: format!("{lo} is not below {hi}"),
            });
        }
    }
    let legend = series
        .iter()
        .enumerate()
        .map(|(i, s)| (Mark::Line(series_colour(i), 3), s.name.clone()))
        .collect();
    let frame = Frame::new(&chart.title, legend, &chart.note, WIDTH)?;
    write_chart(&Drawn { chart, series, frame }, stem)
}

struct Drawn<'a> {
    chart: &'a CurvesChart,
    series: Vec<Series>,
    frame: Frame,
}

impl Chart for Drawn<'_> {
    fn size(&self) -> (u32, u32) {
        (WIDTH, PLOT_HEIGHT + self.frame.extra_height())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<(), DB> {
        let area = self.frame.draw(root)?;
        let all = || self.series.iter().flat_map(|s| s.points.iter());
        let (x0, x1) = super::padded(
            all().map(|p| p.0).fold(f64::INFINITY, f64::min).min(0.0),
            all().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max),
            0.03,
        );
        let (y0, y1) = self.chart.y_range.unwrap_or_else(|| {
            super::padded(
                all().map(|p| p.1).fold(f64::INFINITY, f64::min),
                all().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max),
                0.05,
            )
        });
        let mut plot = ChartBuilder::on(&area)
            .margin_left(10)
            .margin_right(25)
            .margin_top(10)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        let mut mesh = plot.configure_mesh();
        style_mesh(&mut mesh);
        mesh.x_desc(self.chart.x_label.as_str())
            .y_desc(self.chart.y_label.as_str())
            .x_label_formatter(&|v| number_label(*v))
            .y_label_formatter(&|v| number_label(*v))
            .draw()?;
        for (i, s) in self.series.iter().enumerate() {
            let colour = series_colour(i);
            plot.draw_series(LineSeries::new(s.points.iter().copied(), colour.stroke_width(3)))?;
            plot.draw_series(s.points.iter().map(|&p| Circle::new(p, 4, colour.filled())))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{check_chart, temp_dir};
    use super::*;

    fn chart() -> CurvesChart {
        CurvesChart {
            title: "E8: greedy success against training".into(),
            x_label: "gradient steps".into(),
            y_label: "reached the goal (%)".into(),
            y_range: Some((0.0, 100.0)),
            series: vec![
                Series {
                    name: "ours".into(),
                    points: vec![(0.0, 60.0), (20_000.0, 99.5), (10_000.0, 93.0)],
                },
                Series {
                    name: "the paper's".into(),
                    points: vec![(0.0, 0.0), (20_000.0, 0.5)],
                },
            ],
            note: "Each point: the network at that step, greedy, on the same test starts.".into(),
        }
    }

    #[test]
    fn draws_every_series_with_its_legend() {
        let dir = temp_dir("curves");
        let c = chart();
        let files = curves_chart(&c, &dir.join("e8")).unwrap();
        let size = image::open(&files.png).unwrap().to_rgb8().dimensions();
        assert!(size.0 == WIDTH && size.1 > PLOT_HEIGHT);
        check_chart(&files, size, &c.title, 40);
        let svg = std::fs::read_to_string(&files.svg).unwrap();
        for text in ["gradient steps", "reached the goal (%)", "ours", "the paper"] {
            assert!(svg.contains(text), "{text}");
        }
        // A single point and a fitted range draw too.
        let single = CurvesChart {
            y_range: None,
            series: vec![Series {
                name: "one".into(),
                points: vec![(5.0, 5.0)],
            }],
            ..chart()
        };
        curves_chart(&single, &dir.join("single")).unwrap();
    }

    #[test]
    fn bad_charts_are_errors() {
        let dir = temp_dir("curves-bad");
        let stem = dir.join("bad");
        let mut c = chart();
        c.series.clear();
        assert!(matches!(curves_chart(&c, &stem), Err(PlotError::Empty { .. })));
        let mut c = chart();
        c.series[1].points.clear();
        assert!(matches!(curves_chart(&c, &stem), Err(PlotError::Empty { .. })));
        let mut c = chart();
        c.series[0].points[0].1 = f64::NAN;
        assert!(matches!(curves_chart(&c, &stem), Err(PlotError::BadValue { .. })));
        let mut c = chart();
        c.y_range = Some((1.0, 1.0));
        assert!(matches!(curves_chart(&c, &stem), Err(PlotError::Inconsistent { .. })));
    }
}
