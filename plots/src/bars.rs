//! Bar charts of one value per agent (experiment E7).

use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{
    Chart, ChartFiles, FONT_FAMILY, Frame, INK, Mark, PlotError, REFERENCE, Result, TICK_PX, category_chart,
    check_value, diamond, number_label, series_colour, write_chart,
};

/// One bar: a named value, with an optional interval and second value.
#[derive(Clone, Debug, PartialEq)]
pub struct Bar {
    /// The bar's name, written under it (e.g. the agent).
    pub name: String,
    /// The bar's height (e.g. mean steps to goal), also written above it.
    pub value: f64,
    /// An interval drawn as an error bar, `(low, high)` (e.g. a 95% confidence interval of
    /// the mean); `low <= high`.
    pub interval: Option<(f64, f64)>,
    /// A second value drawn as a black diamond on the bar (e.g. the median).
    pub second: Option<f64>,
}

/// A horizontal reference line across the chart, with its legend entry.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    /// The legend's name for it, e.g. "optimum (exact solver)".
    pub label: String,
    /// Where it is drawn on the y axis.
    pub value: f64,
}

/// A bar chart to draw.
#[derive(Clone, Debug, PartialEq)]
pub struct BarChart {
    /// The chart's title.
    pub title: String,
    /// The y axis' description, e.g. "steps to goal".
    pub y_label: String,
    /// The bars, drawn left to right.
    pub bars: Vec<Bar>,
    /// The legend's name for the bars' values, e.g. "mean".
    pub value_label: String,
    /// The legend's name for the intervals, e.g. "95% CI of the mean".
    pub interval_label: String,
    /// The legend's name for the second values, e.g. "median".
    pub second_label: String,
    /// An optional horizontal line, e.g. the optimum, drawn dashed in red.
    pub reference: Option<Reference>,
    /// A logarithmic y axis, for values spanning orders of magnitude (10 to 1000). It
    /// reaches at most 12 decades below the largest value; bars whose value is at or
    /// below zero are left out (their label stays), smaller marks sit on the floor. With
    /// no positive value at all the axis stays linear.
    pub log_scale: bool,
    /// Text drawn under the chart, wrapped to its width; empty for none.
    pub note: String,
}

/// Draws `chart`: one coloured bar per entry with its value written above, error bars
/// for the intervals, diamonds for the second values, the reference as a red dashed
/// line, and a legend naming each kind of mark present. Writes `<stem>.png` and
/// `<stem>.svg`.
///
/// Errors: no bars, an interval whose low end is above its high end, or a value that is
/// not finite or beyond [`super::MAX_VALUE`].
pub fn bar_chart(chart: &BarChart, stem: &Path) -> Result<ChartFiles> {
    if chart.bars.is_empty() {
        return Err(PlotError::Empty { what: "bars".into() });
    }
    for bar in &chart.bars {
        check_value(|| format!("the value of bar {:?}", bar.name), bar.value)?;
        if let Some((lo, hi)) = bar.interval {
            check_value(|| format!("the interval's low end of bar {:?}", bar.name), lo)?;
            check_value(|| format!("the interval's high end of bar {:?}", bar.name), hi)?;
            if lo > hi {
                return Err(PlotError::Inconsistent {
                    what: format!("bar {:?}", bar.name),
                    reason: format!("its interval runs from {lo} down to {hi}"),
                });
            }
        }
        if let Some(s) = bar.second {
            check_value(|| format!("the second value of bar {:?}", bar.name), s)?;
        }
    }
    if let Some(r) = &chart.reference {
        check_value(|| format!("the reference {:?}", r.label), r.value)?;
    }
    let mut legend = vec![(Mark::Block(series_colour(0), 0.8), chart.value_label.clone())];
    if chart.bars.iter().any(|b| b.interval.is_some()) {
        legend.push((Mark::Interval, chart.interval_label.clone()));
    }
    if chart.bars.iter().any(|b| b.second.is_some()) {
        legend.push((Mark::Diamond(BLACK), chart.second_label.clone()));
    }
    if let Some(r) = &chart.reference {
        legend.push((Mark::Dashed(REFERENCE), r.label.clone()));
    }
    let width = 960.max(110 * chart.bars.len() as u32 + 200);
    let drawing = BarDrawing {
        chart,
        frame: Frame::new(&chart.title, legend, &chart.note, width)?,
        width,
    };
    write_chart(&drawing, stem)
}

/// A validated bar chart with its frame laid out.
struct BarDrawing<'a> {
    chart: &'a BarChart,
    frame: Frame,
    width: u32,
}

impl BarDrawing<'_> {
    /// Every value that must fit on the y axis.
    fn values(&self) -> impl Iterator<Item = f64> + '_ {
        let bars = self.chart.bars.iter().flat_map(|b| {
            let (lo, hi) = b.interval.unzip();
            [Some(b.value), lo, hi, b.second].into_iter().flatten()
        });
        bars.chain(self.chart.reference.iter().map(|r| r.value))
    }

    /// Draws the chart over the y axis `y`, whose lowest value is `floor` (where bars
    /// start).
    fn draw_on<DB: DrawingBackend, Y>(&self, root: &DrawingArea<DB, Shift>, y: Y, floor: f64) -> DrawResult<(), DB>
    where
        Y: AsRangedCoord<Value = f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let log = self.chart.log_scale && floor > 0.0;
        let base = if log { floor } else { 0.0 };
        let at = |v: f64| if log { v.max(floor) } else { v };
        let plot_area = self.frame.draw(root)?;
        let bars = &self.chart.bars;
        let n = bars.len();
        let names = bars.iter().map(|b| b.name.clone()).collect();
        let mut chart = category_chart(&plot_area, names, y, &self.chart.y_label)?;

        let half = 0.32;
        let drawn = |b: &&Bar| !log || b.value > 0.0;
        chart.draw_series(bars.iter().enumerate().filter(|(_, b)| drawn(b)).map(|(i, b)| {
            let x = i as f64;
            Rectangle::new(
                [(x - half, base), (x + half, at(b.value))],
                series_colour(i).mix(0.8).filled(),
            )
        }))?;
        chart.draw_series(bars.iter().enumerate().flat_map(|(i, b)| {
            let x = i as f64;
            let cap = half / 3.0;
            b.interval.into_iter().flat_map(move |(lo, hi)| {
                [
                    PathElement::new(vec![(x, at(lo)), (x, at(hi))], INK.stroke_width(2)),
                    PathElement::new(vec![(x - cap, at(lo)), (x + cap, at(lo))], INK.stroke_width(2)),
                    PathElement::new(vec![(x - cap, at(hi)), (x + cap, at(hi))], INK.stroke_width(2)),
                ]
            })
        }))?;
        chart.draw_series(bars.iter().enumerate().filter_map(|(i, b)| {
            b.second
                .map(|s| EmptyElement::at((i as f64, at(s))) + diamond(BLACK) + diamond_outline(WHITE))
        }))?;

        if let Some(r) = &self.chart.reference {
            let (x0, x1) = (-0.5, n as f64 - 0.5);
            chart.draw_series(DashedLineSeries::new(
                [(x0, at(r.value)), (x1, at(r.value))],
                12,
                6,
                REFERENCE.stroke_width(2),
            ))?;
        }

        // Each value above its bar, and above its error bar and diamond where those are higher.
        let above = TextStyle::from((FONT_FAMILY, TICK_PX).into_font())
            .color(&INK)
            .pos(Pos::new(HPos::Center, VPos::Bottom));
        chart.draw_series(bars.iter().enumerate().map(|(i, b)| {
            let top = [b.interval.map(|(_, hi)| hi), b.second]
                .into_iter()
                .flatten()
                .fold(b.value.max(base), f64::max);
            EmptyElement::at((i as f64, at(top))) + Text::new(number_label(b.value), (0, -9), above.clone())
        }))?;
        Ok(())
    }
}

impl Chart for BarDrawing<'_> {
    fn size(&self) -> (u32, u32) {
        (self.width, 600 + self.frame.extra_height())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<(), DB> {
        let (lo, hi) = self
            .values()
            .fold((0.0f64, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
        let positive_min = self.values().filter(|&v| v > 0.0).fold(f64::INFINITY, f64::min);
        // Room above the highest bar for its label: a factor, since the axis is log.
        if let Some((y0, y1)) = super::log_range(positive_min, hi, 2.0, 2.5).filter(|_| self.chart.log_scale) {
            self.draw_on(root, (y0..y1).log_scale(), y0)
        } else {
            let (y0, y1) = if hi > lo {
                (lo, hi + 0.12 * (hi - lo))
            } else {
                super::padded(lo, hi, 0.1)
            };
            let y0 = if lo < 0.0 { y0 - 0.05 * (y1 - y0) } else { y0 };
            self.draw_on(root, y0..y1, y0)
        }
    }
}

/// The outline of [`diamond`], so it stands out on a dark bar.
fn diamond_outline(colour: RGBColor) -> PathElement<(i32, i32)> {
    PathElement::new(vec![(0, -8), (8, 0), (0, 8), (-8, 0), (0, -8)], colour.stroke_width(1))
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{check_chart, listing, temp_dir};
    use super::*;

    fn bar(name: &str, value: f64, interval: Option<(f64, f64)>, second: Option<f64>) -> Bar {
        Bar {
            name: name.into(),
            value,
            interval,
            second,
        }
    }

    fn chart(bars: Vec<Bar>) -> BarChart {
        BarChart {
            title: "E7 steps to goal by agent".into(),
            y_label: "steps to goal".into(),
            bars,
            value_label: "mean".into(),
            interval_label: "95% CI of the mean".into(),
            second_label: "median".into(),
            reference: Some(Reference {
                label: "optimum (exact solver)".into(),
                value: 10.16,
            }),
            log_scale: false,
            note: "500 starts per goal; failures counted at the horizon.".into(),
        }
    }

    fn typical() -> Vec<Bar> {
        vec![
            bar("random", 812.0, Some((790.0, 834.0)), Some(1000.0)),
            bar("Q (paper)", 41.5, Some((38.0, 45.0)), Some(33.0)),
            bar("Q (ours)", 14.2, Some((13.5, 14.9)), Some(13.0)),
            bar("oracle", 10.9, None, Some(10.0)),
            bar("exact", 10.16, None, None),
        ]
    }

    #[test]
    fn writes_png_and_svg_linear_and_log() {
        let dir = temp_dir("bars");
        for log_scale in [false, true] {
            let mut c = chart(typical());
            c.log_scale = log_scale;
            let files = bar_chart(&c, &dir.join(format!("e7-{log_scale}"))).expect("drawn");
            let size = image::open(&files.png).expect("png").to_rgb8().dimensions();
            assert_eq!(size.0, 960);
            check_chart(&files, size, &c.title, 40);
            let svg = std::fs::read_to_string(&files.svg).expect("svg");
            for text in [
                "Q (paper)",
                "exact",
                "optimum (exact solver)",
                "95% CI of the mean",
                "median",
                "812",
            ] {
                assert!(svg.contains(text), "svg lacks {text:?}");
            }
        }
        assert_eq!(listing(&dir).len(), 4);
    }

    #[test]
    fn odd_but_valid_bars_still_draw() {
        let dir = temp_dir("bars-odd");
        let cases = [
            ("single", vec![bar("only", 7.0, None, None)]),
            (
                "zeros",
                vec![bar("a", 0.0, None, None), bar("b", 0.0, Some((0.0, 0.0)), None)],
            ),
            (
                "negative",
                vec![
                    bar("a", -3.0, Some((-4.0, -2.0)), Some(-3.5)),
                    bar("b", 2.0, None, None),
                ],
            ),
            (
                "huge",
                vec![
                    bar("a", 1e15, Some((1e15, 1e15)), None),
                    bar("b", 1.0, None, Some(-1e15)),
                ],
            ),
            ("equal", vec![bar("a", 5.0, None, None); 4]),
            (
                "many",
                (0..15)
                    .map(|i| bar(&format!("agent {i}"), f64::from(i) * 70.0, None, None))
                    .collect(),
            ),
        ];
        for (name, bars) in cases {
            for log_scale in [false, true] {
                let mut c = chart(bars.clone());
                c.log_scale = log_scale;
                c.reference = None;
                let files =
                    bar_chart(&c, &dir.join(format!("{name}-{log_scale}"))).unwrap_or_else(|e| panic!("{name}: {e}"));
                let size = image::open(&files.png).expect("png").to_rgb8().dimensions();
                check_chart(&files, size, &c.title, 40);
            }
        }
    }

    #[test]
    fn bad_bars_are_errors() {
        let dir = temp_dir("bars-bad");
        let stem = dir.join("bad");
        assert!(matches!(bar_chart(&chart(vec![]), &stem), Err(PlotError::Empty { .. })));
        let err = bar_chart(&chart(vec![bar("a", 5.0, Some((6.0, 4.0)), None)]), &stem).unwrap_err();
        assert!(err.to_string().contains("from 6 down to 4"), "{err}");
        for bad in [f64::NAN, f64::INFINITY, -2e15] {
            assert!(bar_chart(&chart(vec![bar("a", bad, None, None)]), &stem).is_err());
            assert!(bar_chart(&chart(vec![bar("a", 1.0, Some((bad, 1.0)), None)]), &stem).is_err());
            assert!(bar_chart(&chart(vec![bar("a", 1.0, None, Some(bad))]), &stem).is_err());
            let mut c = chart(typical());
            c.reference.as_mut().expect("reference").value = bad;
            assert!(matches!(bar_chart(&c, &stem), Err(PlotError::BadValue { .. })));
        }
        assert!(listing(&dir).is_empty());
    }
}
