//! Static SVG charts for the generated reports: points with error bars,
//! curves, optional labels and a log-scaled x axis. Standalone files with
//! no scripts or external references, so they render in any viewer and in
//! a Markdown preview.

use std::fmt::Write;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Style {
    /// Markers with vertical error bars.
    Points,
    /// A solid line through the points (theory curves).
    Line,
    /// A dashed line.
    Dashed,
    /// Open markers (values quoted from the paper).
    Open,
}

#[derive(Debug, Clone)]
pub struct Series {
    pub name: String,
    pub style: Style,
    /// (x, y, error bar half-height).
    pub points: Vec<(f64, f64, f64)>,
    /// A text beside each point (same order as `points`), or none.
    pub labels: Vec<String>,
}

impl Series {
    pub fn new(name: impl Into<String>, style: Style) -> Self {
        Series {
            name: name.into(),
            style,
            points: Vec::new(),
            labels: Vec::new(),
        }
    }

    pub fn point(mut self, x: f64, y: f64, err: f64) -> Self {
        self.points.push((x, y, err));
        self
    }

    pub fn labelled(mut self, x: f64, y: f64, err: f64, label: impl Into<String>) -> Self {
        self.points.push((x, y, err));
        self.labels.push(label.into());
        self
    }
}

#[derive(Debug, Clone)]
pub struct Chart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub series: Vec<Series>,
    /// A horizontal reference line (e.g. zero shift).
    pub y_rule: Option<f64>,
}

const COLOURS: [&str; 6] = [
    "#1f5fa8", "#c0392b", "#2e8b57", "#8e44ad", "#d68910", "#555555",
];
const W: f64 = 640.0;
const H: f64 = 400.0;
const LEFT: f64 = 64.0;
const RIGHT: f64 = 170.0;
const TOP: f64 = 36.0;
const BOTTOM: f64 = 52.0;

impl Chart {
    pub fn new(title: &str, x_label: &str, y_label: &str) -> Self {
        Chart {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            log_x: false,
            series: Vec::new(),
            y_rule: None,
        }
    }

    fn x_of(&self, x: f64) -> f64 {
        if self.log_x {
            x.max(1e-300).log10()
        } else {
            x
        }
    }

    /// The data ranges with padding, in plotted coordinates.
    fn frame(&self) -> Frame {
        let mut xs: Vec<f64> = Vec::new();
        let mut ys: Vec<f64> = Vec::new();
        for s in &self.series {
            for &(x, y, e) in &s.points {
                if x.is_finite() && y.is_finite() {
                    xs.push(self.x_of(x));
                    let e = if e.is_finite() { e } else { 0.0 };
                    ys.push(y - e);
                    ys.push(y + e);
                }
            }
        }
        if let Some(r) = self.y_rule {
            ys.push(r);
        }
        let (x0, x1) = padded_range(&xs);
        let (y0, y1) = padded_range(&ys);
        Frame {
            x0,
            x1,
            y0,
            y1,
            log_x: self.log_x,
        }
    }

    /// The chart as a standalone SVG document.
    pub fn svg(&self) -> String {
        let f = self.frame();
        // Wide enough for the longest legend entry (about 7 px a character at 12 px).
        let longest = self
            .series
            .iter()
            .map(|x| x.name.chars().count())
            .max()
            .unwrap_or(0);
        let width = W.max(W - RIGHT + 40.0 + 7.0 * longest as f64).ceil();
        let mut s = String::new();
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{H}" viewBox="0 0 {width} {H}" font-family="sans-serif" font-size="12">"#
        );
        let _ = writeln!(s, r##"<rect width="100%" height="100%" fill="#ffffff"/>"##);
        let _ = writeln!(
            s,
            r##"<text x="{}" y="20" font-size="14" font-weight="bold">{}</text>"##,
            LEFT,
            esc(&self.title)
        );
        s.push_str(&self.axes(&f));
        for (k, series) in self.series.iter().enumerate() {
            let c = COLOURS[k % COLOURS.len()];
            s.push_str(&series.svg(&f, c));
            s.push_str(&series.legend_entry(k, c));
        }
        s.push_str("</svg>\n");
        s
    }

    /// The frame, grid, ticks, axis labels and the reference line.
    fn axes(&self, f: &Frame) -> String {
        let mut s = String::new();
        let (pw, ph) = (PW, PH);
        let _ = writeln!(
            s,
            r##"<rect x="{LEFT}" y="{TOP}" width="{pw}" height="{ph}" fill="none" stroke="#333"/>"##
        );
        for t in ticks(f.y0, f.y1) {
            let y = f.py(t);
            let _ = writeln!(
                s,
                r##"<line x1="{LEFT}" x2="{}" y1="{y:.1}" y2="{y:.1}" stroke="#e4e4e4"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"##,
                LEFT + pw,
                LEFT - 6.0,
                y + 4.0,
                tick_label(t)
            );
        }
        for (t, label) in f.x_ticks() {
            let x = LEFT + (t - f.x0) / (f.x1 - f.x0) * pw;
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" x2="{x:.1}" y1="{TOP}" y2="{}" stroke="#e4e4e4"/><text x="{x:.1}" y="{}" text-anchor="middle">{label}</text>"##,
                TOP + ph,
                TOP + ph + 16.0
            );
        }
        let _ = writeln!(
            s,
            r##"<text x="{}" y="{}" text-anchor="middle">{}</text>"##,
            LEFT + pw / 2.0,
            H - 12.0,
            esc(&self.x_label)
        );
        let _ = writeln!(
            s,
            r##"<text transform="translate(16 {}) rotate(-90)" text-anchor="middle">{}</text>"##,
            TOP + ph / 2.0,
            esc(&self.y_label)
        );
        if let Some(r) = self.y_rule {
            let y = f.py(r);
            let _ = writeln!(
                s,
                r##"<line x1="{LEFT}" x2="{}" y1="{y:.1}" y2="{y:.1}" stroke="#888" stroke-dasharray="2 3"/>"##,
                LEFT + pw
            );
        }
        s
    }
}

/// Width and height of the plotting area.
const PW: f64 = W - LEFT - RIGHT;
const PH: f64 = H - TOP - BOTTOM;

/// The plotted ranges and the map from data to the page.
struct Frame {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    log_x: bool,
}

impl Frame {
    fn px(&self, x: f64) -> f64 {
        let x = if self.log_x { x.max(1e-300).log10() } else { x };
        LEFT + (x - self.x0) / (self.x1 - self.x0) * PW
    }

    fn py(&self, y: f64) -> f64 {
        TOP + (self.y1 - y) / (self.y1 - self.y0) * PH
    }

    /// Tick positions (in plotted coordinates) with their labels; 1, 2, 5
    /// per decade on a log axis, or only the powers of ten where it spans
    /// more than three decades (their labels would run into each other).
    fn x_ticks(&self) -> Vec<(f64, String)> {
        if !self.log_x {
            return ticks(self.x0, self.x1)
                .into_iter()
                .map(|t| (t, tick_label(t)))
                .collect();
        }
        let (a, b) = (self.x0.floor() as i32, self.x1.ceil() as i32);
        let mantissas: &[f64] = if self.x1 - self.x0 > 3.0 {
            &[1.0]
        } else {
            &[1.0, 2.0, 5.0]
        };
        let mut v = Vec::new();
        for e in a..=b {
            for &m in mantissas {
                let l = (m * 10f64.powi(e)).log10();
                if l >= self.x0 && l <= self.x1 {
                    v.push((l, tick_label(m * 10f64.powi(e))));
                }
            }
        }
        v
    }
}

impl Series {
    /// Its line, or its markers with error bars and labels.
    fn svg(&self, f: &Frame, c: &str) -> String {
        let mut s = String::new();
        let pts: Vec<(f64, f64, f64)> = self
            .points
            .iter()
            .copied()
            .filter(|&(x, y, _)| x.is_finite() && y.is_finite())
            .collect();
        if matches!(self.style, Style::Line | Style::Dashed) {
            let d: Vec<String> = pts
                .iter()
                .map(|&(x, y, _)| format!("{:.1},{:.1}", f.px(x), f.py(y)))
                .collect();
            let dash = if self.style == Style::Dashed {
                r#" stroke-dasharray="6 4""#
            } else {
                ""
            };
            let _ = writeln!(
                s,
                r##"<polyline points="{}" fill="none" stroke="{c}" stroke-width="1.5"{dash}/>"##,
                d.join(" ")
            );
            return s;
        }
        let open = self.style == Style::Open;
        let fill = if open { "#ffffff" } else { c };
        for (i, &(x, y, e)) in pts.iter().enumerate() {
            let (cx, cy) = (f.px(x), f.py(y));
            if e.is_finite() && e > 0.0 {
                let _ = writeln!(
                    s,
                    r##"<line x1="{cx:.1}" x2="{cx:.1}" y1="{:.1}" y2="{:.1}" stroke="{c}"/>"##,
                    f.py(y - e),
                    f.py(y + e)
                );
            }
            if open {
                let _ = writeln!(
                    s,
                    r##"<rect x="{:.1}" y="{:.1}" width="8" height="8" fill="{fill}" stroke="{c}" stroke-width="1.5"/>"##,
                    cx - 4.0,
                    cy - 4.0
                );
            } else {
                let _ = writeln!(
                    s,
                    r##"<circle cx="{cx:.1}" cy="{cy:.1}" r="4" fill="{fill}"/>"##
                );
            }
            if let Some(label) = self.labels.get(i) {
                let _ = writeln!(
                    s,
                    r##"<text x="{:.1}" y="{:.1}" font-size="10" fill="{c}">{}</text>"##,
                    cx + 6.0,
                    cy - 5.0,
                    esc(label)
                );
            }
        }
        s
    }

    /// Its line in the legend, the `k`-th.
    fn legend_entry(&self, k: usize, c: &str) -> String {
        let ly = TOP + 14.0 + 18.0 * k as f64;
        let lx = W - RIGHT + 14.0;
        let mark = match self.style {
            Style::Line => format!(
                r##"<line x1="{lx}" x2="{}" y1="{ly}" y2="{ly}" stroke="{c}" stroke-width="1.5"/>"##,
                lx + 16.0
            ),
            Style::Dashed => format!(
                r##"<line x1="{lx}" x2="{}" y1="{ly}" y2="{ly}" stroke="{c}" stroke-width="1.5" stroke-dasharray="6 4"/>"##,
                lx + 16.0
            ),
            Style::Points => format!(
                r##"<circle cx="{}" cy="{ly}" r="4" fill="{c}"/>"##,
                lx + 8.0
            ),
            Style::Open => format!(
                r##"<rect x="{}" y="{}" width="8" height="8" fill="#fff" stroke="{c}" stroke-width="1.5"/>"##,
                lx + 4.0,
                ly - 4.0
            ),
        };
        format!(
            "{mark}<text x=\"{}\" y=\"{}\">{}</text>\n",
            lx + 22.0,
            ly + 4.0,
            esc(&self.name)
        )
    }
}

/// The data range with 6 % padding (a unit range around a single value).
fn padded_range(v: &[f64]) -> (f64, f64) {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() || !hi.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-12 {
        return (lo - 0.5, hi + 0.5);
    }
    let pad = 0.06 * (hi - lo);
    (lo - pad, hi + pad)
}

/// Round tick values (1, 2 or 5 times a power of ten apart) inside a range.
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = hi - lo;
    let raw = span / 6.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * mag)
        .find(|s| span / s <= 7.0)
        .unwrap_or(10.0 * mag);
    let mut t = (lo / step).ceil() * step;
    let mut v = Vec::new();
    while t <= hi + 1e-9 * step {
        v.push(if t.abs() < 1e-9 * step { 0.0 } else { t });
        t += step;
    }
    v
}

fn tick_label(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        format!("{v:.0e}")
    } else if (v - v.round()).abs() < 1e-9 {
        format!("{}", v.round())
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_inside() {
        let t = ticks(0.3, 9.7);
        assert_eq!(t, vec![2.0, 4.0, 6.0, 8.0]);
        assert!(ticks(-1.2, 1.3).contains(&0.0));
    }

    #[test]
    fn a_wide_log_axis_labels_only_powers_of_ten() {
        let chart = |hi: f64| {
            let mut c = Chart::new("t", "x", "y");
            c.log_x = true;
            c.series.push(
                Series::new("a", Style::Points)
                    .point(0.2, 1.0, 0.0)
                    .point(hi, 2.0, 0.0),
            );
            c.svg()
        };
        let wide = chart(1e5);
        assert!(
            wide.contains(">1000<") && !wide.contains(">2000<"),
            "{wide}"
        );
        let narrow = chart(50.0);
        assert!(narrow.contains(">2<") && narrow.contains(">5<"), "{narrow}");
    }

    #[test]
    fn draws_each_point_error_bar_and_legend() {
        let mut c = Chart::new("t", "x", "y");
        c.series.push(
            Series::new("a & b", Style::Points)
                .point(1.0, 2.0, 0.5)
                .point(2.0, f64::NAN, 0.0),
        );
        c.series
            .push(Series::new("theory", Style::Line).point(0.0, 0.0, 0.0));
        let svg = c.svg();
        // one finite point: one marker + the legend marker
        assert_eq!(svg.matches("<circle").count(), 2);
        assert_eq!(svg.matches("<polyline").count(), 1);
        assert!(svg.contains("a &amp; b"));
        assert!(!svg.contains("NaN"));
    }
}
