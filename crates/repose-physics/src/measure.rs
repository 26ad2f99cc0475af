//! Measuring a pile: the surface profile `h(x)` along a horizontal axis and
//! its slope by the three methods of Lee & Herrmann (section 3), in any
//! dimension (the vertical axis is the last one: y in 2D, z in 3D).

pub use crate::report::Profile;
use repose_engine::dim::Vector;
use serde::{Deserialize, Serialize};

/// The slope of one pile by each method, as angles in degrees (positive
/// when the surface falls towards the open side, +x).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SlopeAngles {
    /// Method 1: the line through the first and last columns.
    pub endpoints: f64,
    /// Method 2: least-squares line through `h(x)`.
    pub line_fit: f64,
    /// Method 3 (the paper's headline): least-squares parabola through the
    /// running sum of `h`, whose curvature gives the slope.
    pub cumulative_fit: f64,
}

impl Profile {
    /// Builds the profile over `[lo, hi]` along `axis` from grain centres
    /// and radii, in columns one mean diameter wide; a grain belongs to the
    /// column holding its centre, and its top is its height plus its radius
    /// along the last axis. Grains outside `[lo, hi)` are ignored.
    pub fn measure<const D: usize>(
        pos: &[Vector<D>],
        radius: &[f64],
        axis: usize,
        lo: f64,
        hi: f64,
    ) -> Profile {
        let width = hi - lo;
        let cells = Profile::columns(radius, width);
        let w = width / cells as f64;
        let mut h = vec![0.0f64; cells];
        for (x, r) in pos.iter().zip(radius) {
            let along = x[axis] - lo;
            if along < 0.0 || along >= width {
                continue;
            }
            let k = ((along / w) as usize).min(cells - 1);
            h[k] = h[k].max(x[D - 1] + r);
        }
        let xs = (0..cells).map(|k| lo + (k as f64 + 0.5) * w).collect();
        Profile {
            axis,
            cell_width: w,
            x: xs,
            h,
        }
    }

    /// How many columns one mean diameter wide tile a span `width` (at least two).
    fn columns(radius: &[f64], width: f64) -> usize {
        let mean_d = if radius.is_empty() {
            0.2
        } else {
            2.0 * radius.iter().sum::<f64>() / radius.len() as f64
        };
        ((width / mean_d).round() as usize).max(2)
    }

    /// The silhouette of the grains seen along the other horizontal axis,
    /// sampled `per_diameter` times a mean diameter over `[lo, hi]`: at each
    /// sample the highest point of any sphere above it, the centre's height
    /// plus the half chord √(r² − Δx²). This is the upper boundary of the
    /// grains' projection that an image of the pile shows; the column
    /// profile of [`Profile::measure`] lifts each column to the top of its
    /// highest grain across the whole width, so it stands above the
    /// silhouette by a fraction of a grain wherever the surface is rough.
    pub fn silhouette<const D: usize>(
        pos: &[Vector<D>],
        radius: &[f64],
        axis: usize,
        lo: f64,
        hi: f64,
        per_diameter: usize,
    ) -> Profile {
        let samples = Profile::columns(radius, hi - lo) * per_diameter.max(1);
        let w = (hi - lo) / samples as f64;
        let mut h = vec![0.0f64; samples];
        for (x, &r) in pos.iter().zip(radius) {
            let centre = x[axis] - lo;
            let first = ((centre - r) / w).floor().max(0.0) as usize;
            let last = (((centre + r) / w).floor().max(0.0) as usize).min(samples - 1);
            for (k, top) in h.iter_mut().enumerate().take(last + 1).skip(first) {
                let dx = (k as f64 + 0.5) * w - centre;
                if dx.abs() < r {
                    *top = top.max(x[D - 1] + (r * r - dx * dx).sqrt());
                }
            }
        }
        let xs = (0..samples).map(|k| lo + (k as f64 + 0.5) * w).collect();
        Profile {
            axis,
            cell_width: w,
            x: xs,
            h,
        }
    }

    /// Whether this surface is a pile whose slope is an angle of repose:
    /// at least three columns hold grains, and the fitted surface falls
    /// towards the open side, or is level to within a grain.
    pub fn check(&self, angles: &SlopeAngles) -> Result<(), String> {
        let occupied = self.h.iter().filter(|h| **h > 0.0).count();
        if occupied < 3 {
            return Err(format!(
                "only {occupied} of {} columns hold grains after the release: too few to measure a slope",
                self.h.len()
            ));
        }
        // A level surface is rough by about a grain: a rise smaller than one
        // column width across the box is noise around zero.
        let span = self.x[self.x.len() - 1] - self.x[0];
        let tolerance = (self.cell_width / span).atan().to_degrees();
        if angles.cumulative_fit < -tolerance {
            return Err(format!(
                "the surface rises towards the open side ({:.2}° by method 3): the fill stood without avalanching, so its slope is not an angle of repose",
                angles.cumulative_fit
            ));
        }
        Ok(())
    }

    /// The three slope estimates of section 3.
    pub fn slope_angles(&self) -> SlopeAngles {
        let n = self.h.len();
        let endpoints = (self.h[n - 1] - self.h[0]) / (self.x[n - 1] - self.x[0]);
        let line = polyfit(&self.x, &self.h, 1)[1];
        let mut running = 0.0;
        let sums: Vec<f64> = self
            .h
            .iter()
            .map(|h| {
                running += h;
                running
            })
            .collect();
        // If h = a + b x, the running sum is a parabola in x with curvature b / (2w).
        let curvature = polyfit(&self.x, &sums, 2)[2];
        let cumulative = 2.0 * self.cell_width * curvature;
        let angle = |slope: f64| (-slope).atan().to_degrees();
        SlopeAngles {
            endpoints: angle(endpoints),
            line_fit: angle(line),
            cumulative_fit: angle(cumulative),
        }
    }
}

/// Least-squares polynomial of the given degree (≤ 2); returns the
/// coefficients from the constant term up. Centred for conditioning.
#[allow(clippy::needless_range_loop)] // row operations read clearer with indices
fn polyfit(x: &[f64], y: &[f64], degree: usize) -> Vec<f64> {
    let n = x.len() as f64;
    let xm = x.iter().sum::<f64>() / n;
    let m = degree + 1;
    // Normal equations in u = x − xm.
    let mut a = [[0.0f64; 4]; 3];
    for (&xi, &yi) in x.iter().zip(y) {
        let u = xi - xm;
        let powers = [1.0, u, u * u, u * u * u, u * u * u * u];
        for r in 0..m {
            for c in 0..m {
                a[r][c] += powers[r + c];
            }
            a[r][m] += powers[r] * yi;
        }
    }
    // Gaussian elimination with partial pivoting on the m × (m+1) system.
    for col in 0..m {
        let pivot = (col..m)
            .max_by(|&p, &q| a[p][col].abs().total_cmp(&a[q][col].abs()))
            .unwrap_or(col);
        a.swap(col, pivot);
        for r in 0..m {
            if r != col && a[col][col] != 0.0 {
                let f = a[r][col] / a[col][col];
                for c in col..=m {
                    a[r][c] -= f * a[col][c];
                }
            }
        }
    }
    let c: Vec<f64> = (0..m)
        .map(|r| {
            if a[r][r] != 0.0 {
                a[r][m] / a[r][r]
            } else {
                0.0
            }
        })
        .collect();
    // Back to powers of x: p(u) with u = x − xm.
    match degree {
        1 => vec![c[0] - c[1] * xm, c[1]],
        2 => vec![
            c[0] - c[1] * xm + c[2] * xm * xm,
            c[1] - 2.0 * c[2] * xm,
            c[2],
        ],
        _ => c,
    }
}

/// Mean, sample standard deviation and standard error of a series.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    pub n: usize,
    pub mean: f64,
    /// Sample standard deviation (n − 1), the paper's error bar.
    pub sd: f64,
    /// Standard error of the mean.
    pub sem: f64,
}

impl Stats {
    pub fn of(values: &[f64]) -> Option<Stats> {
        let n = values.len();
        if n == 0 {
            return None;
        }
        let mean = values.iter().sum::<f64>() / n as f64;
        let sd = if n > 1 {
            (values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        Some(Stats {
            n,
            mean,
            sd,
            sem: sd / (n as f64).sqrt(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn surface_of(f: impl Fn(f64) -> f64) -> Profile {
        let cells = 20;
        let w = 0.2;
        let x: Vec<f64> = (0..cells).map(|k| (k as f64 + 0.5) * w).collect();
        let h = x.iter().map(|&x| f(x)).collect();
        Profile {
            axis: 0,
            cell_width: w,
            x,
            h,
        }
    }

    #[test]
    fn all_three_methods_agree_on_a_straight_slope() {
        let s = surface_of(|x| 3.0 - 0.5 * x);
        let a = s.slope_angles();
        let expected = 0.5f64.atan().to_degrees();
        for v in [a.endpoints, a.line_fit, a.cumulative_fit] {
            assert!((v - expected).abs() < 1e-9, "{a:?}");
        }
    }

    #[test]
    fn methods_differ_on_a_curved_surface_as_the_paper_reports() {
        // A surface that steepens at the ends: the endpoint line sees the ends only.
        let s = surface_of(|x| 3.0 - 0.4 * x - 0.05 * (x - 2.0).powi(3));
        let a = s.slope_angles();
        assert!(a.endpoints > a.line_fit, "{a:?}");
    }

    #[test]
    fn profile_takes_the_highest_top_in_each_column() {
        let pos = vec![
            Vector::<2>::new(0.1, 0.1),
            Vector::<2>::new(0.15, 0.3),
            Vector::<2>::new(3.9, 0.1),
        ];
        let radius = vec![0.1, 0.1, 0.1];
        let s = Profile::measure(&pos, &radius, 0, 0.0, 4.0);
        assert_eq!(s.h.len(), 20);
        assert!((s.h[0] - 0.4).abs() < 1e-12);
        assert!((s.h[19] - 0.2).abs() < 1e-12);
        assert_eq!(s.h[5], 0.0);
    }

    #[test]
    fn a_profile_in_3d_projects_along_either_horizontal_axis() {
        // Two spheres: one at (0.1, 0.9) high, one at (0.9, 0.1) low.
        let pos = vec![
            Vector::<3>::new(0.1, 0.9, 0.5),
            Vector::<3>::new(0.9, 0.1, 0.1),
        ];
        let radius = vec![0.1, 0.1];
        let along_x = Profile::measure(&pos, &radius, 0, 0.0, 1.0);
        let along_y = Profile::measure(&pos, &radius, 1, 0.0, 1.0);
        assert!((along_x.h[0] - 0.6).abs() < 1e-12 && (along_x.h[4] - 0.2).abs() < 1e-12);
        assert!((along_y.h[0] - 0.2).abs() < 1e-12 && (along_y.h[4] - 0.6).abs() < 1e-12);
    }

    /// Area under a profile.
    fn area(p: &Profile) -> f64 {
        p.h.iter().sum::<f64>() * p.cell_width
    }

    #[test]
    fn the_silhouette_of_a_resting_sphere_is_its_disc_on_a_rectangle() {
        // A sphere of radius r resting on the floor, seen from the side:
        // the area under its top is the lower half-square 2r² plus the
        // upper half-disc πr²/2, whatever the column width.
        let r = 0.5;
        let pos = vec![Vector::<3>::new(2.3, 1.0, r)];
        let exact = 2.0 * r * r + std::f64::consts::PI * r * r / 2.0;
        let fine = Profile::silhouette(&pos, &[r], 0, 0.0, 5.0, 200);
        assert!(
            (area(&fine) - exact).abs() < 1e-4 * exact,
            "{}",
            area(&fine)
        );
        // The column profile fills its whole column to the sphere's top.
        let columns = Profile::measure(&pos, &[r], 0, 0.0, 5.0);
        assert!((area(&columns) - 2.0 * r * columns.cell_width).abs() < 1e-12);
    }

    #[test]
    fn the_silhouette_takes_the_highest_sphere_at_each_point_of_a_row() {
        // Two touching spheres, the second raised by h: where their discs
        // overlap in projection the higher one hides the lower.
        let (r, h) = (0.5, 0.3);
        let pos = vec![
            Vector::<3>::new(1.0, 0.0, r),
            Vector::<3>::new(1.8, 0.7, r + h),
        ];
        let s = Profile::silhouette(&pos, &[r, r], 0, 0.0, 3.0, 400);
        for (x, top) in s.x.iter().zip(&s.h) {
            let cap = |c: f64, z: f64| {
                let dx = x - c;
                if dx.abs() < r {
                    z + (r * r - dx * dx).sqrt()
                } else {
                    0.0
                }
            };
            let expected = cap(1.0, r).max(cap(1.8, r + h));
            assert!(
                (top - expected).abs() < 1e-12,
                "at x = {x}: {top} against {expected}"
            );
        }
        // Seen along the row (axis 1), the two discs lie side by side.
        let across = Profile::silhouette(&pos, &[r, r], 1, -1.0, 2.0, 400);
        assert!((across.h.iter().cloned().fold(0.0, f64::max) - (2.0 * r + h)).abs() < 1e-5);
    }

    #[test]
    fn the_column_profile_stands_above_the_silhouette_of_a_rough_surface() {
        // Grains scattered at uneven heights: each column reaches the top of
        // its highest grain across its whole width, the silhouette only at
        // that grain's crown.
        let mut pos = Vec::new();
        let mut radius = Vec::new();
        for k in 0..60 {
            let u = (k as f64 * 0.618_033_988_75).fract();
            let v = (k as f64 * 0.414_213_562_37).fract();
            pos.push(Vector::<3>::new(0.5 + 9.0 * u, 0.0, 0.5 + 3.0 * v));
            radius.push(0.45 + 0.1 * v);
        }
        let columns = Profile::measure(&pos, &radius, 0, 0.0, 10.0);
        let fine = Profile::silhouette(&pos, &radius, 0, 0.0, 10.0, 20);
        assert!(area(&fine) < area(&columns));
        assert!(area(&fine) > 0.8 * area(&columns));
    }

    #[test]
    fn stats_use_the_sample_standard_deviation() {
        let s = Stats::of(&[1.0, 2.0, 3.0, 4.0]).unwrap();
        assert_eq!(s.mean, 2.5);
        assert!((s.sd - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert!((s.sem - s.sd / 2.0).abs() < 1e-12);
    }
}
