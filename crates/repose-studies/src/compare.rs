//! A paper's stated results against ours: each row a quantity, the paper's
//! value or statement, our statistics, the difference in combined standard
//! errors and a verdict.

use repose_store::Aggregate;
use serde::{Deserialize, Serialize};

/// One line of the comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Comparison {
    pub quantity: String,
    /// The paper's value or statement.
    pub paper: String,
    pub ours: Option<Aggregate>,
    /// (ours − paper) in combined standard errors, where both are numbers.
    pub sigma: Option<f64>,
    /// `agrees`, `differs`, `not resolved` or `no result`.
    pub verdict: String,
    /// Why it differs, or what the number rests on.
    pub reason: String,
}

/// Two differences within this many combined standard errors agree.
pub const AGREEMENT: f64 = 2.0;

impl Comparison {
    /// Ours against a value the paper quotes as mean ± sd over `n` samples.
    pub fn quoted(
        quantity: String,
        (mean, sd, n): (f64, f64, f64),
        ours: Option<Aggregate>,
        why_differs: &str,
    ) -> Comparison {
        let sigma = ours.and_then(|o| {
            let se = (o.sem.unwrap_or(0.0).powi(2) + sd * sd / n).sqrt();
            Some((o.mean? - mean) / se)
        });
        let verdict = verdict(sigma);
        Comparison {
            quantity,
            paper: format!("{mean:.2} ± {sd:.2} (n={n})"),
            ours,
            sigma,
            reason: if verdict == "differs" {
                why_differs.to_string()
            } else {
                String::new()
            },
            verdict,
        }
    }

    /// A qualitative statement of the paper, judged by `agrees`.
    pub fn statement(
        quantity: impl Into<String>,
        paper: impl Into<String>,
        ours: Option<Aggregate>,
        sigma: Option<f64>,
        agrees: bool,
        reason: impl Into<String>,
    ) -> Comparison {
        Comparison {
            quantity: quantity.into(),
            paper: paper.into(),
            ours,
            sigma,
            verdict: if agrees { "agrees" } else { "differs" }.into(),
            reason: reason.into(),
        }
    }
}

impl Comparison {
    /// The same row with another verdict (`no result`, `not resolved`).
    pub fn with_verdict(mut self, verdict: &str) -> Comparison {
        self.verdict = verdict.to_string();
        self
    }
}

/// `agrees` within [`AGREEMENT`] standard errors, else `differs`.
pub fn verdict(sigma: Option<f64>) -> String {
    match sigma {
        None => "no result".into(),
        Some(s) if s.abs() <= AGREEMENT => "agrees".into(),
        Some(_) => "differs".into(),
    }
}

/// `mean ± sd (n=…)`, a fitted constant as `value ± se (se)`, or a dash.
pub fn fmt_agg(a: Option<Aggregate>) -> String {
    match a {
        Some(Aggregate {
            n,
            mean: Some(m),
            sd,
            sem,
        }) => match (sd, sem) {
            // A fitted constant: its standard error.
            (None, Some(se)) => format!("{m:.4} ± {se:.4} (se)"),
            _ => format!("{m:.2} ± {:.2} (n={n})", sd.unwrap_or(0.0)),
        },
        _ => "—".into(),
    }
}

/// Weighted least-squares slope of `y` against `x` (weights 1/sem²) with
/// its standard error, from at least two points.
pub fn weighted_slope(points: &[(f64, Aggregate)]) -> Option<(f64, f64)> {
    if points.len() < 2 {
        return None;
    }
    let (mut sw, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (x, a) in points {
        let y = a.mean?;
        let w = 1.0 / a.sem.unwrap_or(0.0).max(1e-6).powi(2);
        sw += w;
        sx += w * x;
        sy += w * y;
        sxx += w * x * x;
        sxy += w * x * y;
    }
    let d = sw * sxx - sx * sx;
    (d > 0.0).then(|| ((sw * sxy - sx * sy) / d, (sw / d).sqrt()))
}

/// Least-squares slope of `y` against `x` for points that scatter alike,
/// each weighted by its sample count, with its standard error: the larger
/// of the one from the scatter within the points (pooled over them) and
/// the one from the scatter of their means about the line (which holds
/// what the line does not describe). For points of a few samples each,
/// whose own standard errors are too rough to weight by. At least two
/// points with samples, and a pooled scatter or a third point.
pub fn pooled_slope(points: &[(f64, Aggregate)]) -> Option<(f64, f64)> {
    let pts: Vec<(f64, f64, f64)> = points
        .iter()
        .filter_map(|(x, a)| Some((*x, a.mean?, a.n as f64)))
        .filter(|p| p.2 > 0.0)
        .collect();
    let w: f64 = pts.iter().map(|p| p.2).sum();
    let xm = pts.iter().map(|p| p.2 * p.0).sum::<f64>() / w;
    let ym = pts.iter().map(|p| p.2 * p.1).sum::<f64>() / w;
    let sxx: f64 = pts.iter().map(|p| p.2 * (p.0 - xm).powi(2)).sum();
    if pts.len() < 2 || sxx <= 0.0 {
        return None;
    }
    let slope = pts
        .iter()
        .map(|p| p.2 * (p.0 - xm) * (p.1 - ym))
        .sum::<f64>()
        / sxx;
    let within = pooled_variance(points).map(|s2| (s2 / sxx).sqrt());
    let about = (pts.len() > 2).then(|| {
        let r2: f64 = pts
            .iter()
            .map(|p| p.2 * (p.1 - ym - slope * (p.0 - xm)).powi(2))
            .sum();
        (r2 / (pts.len() - 2) as f64 / sxx).sqrt()
    });
    let se = match (within, about) {
        (Some(a), Some(b)) => a.max(b),
        (a, b) => a.or(b)?,
    };
    Some((slope, se))
}

/// The variance within points pooled over them, Σ (n − 1) sd² over
/// Σ (n − 1): one scatter for points that scatter alike, resting on all
/// their degrees of freedom rather than each point's few.
pub fn pooled_variance(points: &[(f64, Aggregate)]) -> Option<f64> {
    let (ss, dof) = points
        .iter()
        .fold((0.0, 0.0), |(ss, dof), (_, a)| match (a.sd, a.n > 1) {
            (Some(sd), true) => (ss + (a.n - 1) as f64 * sd * sd, dof + (a.n - 1) as f64),
            _ => (ss, dof),
        });
    (dof > 0.0).then(|| ss / dof)
}

/// The plain mean of the points' means, with its standard error from the
/// pooled variance s² ([`pooled_variance`]): √(s² Σ 1/n) / K over K
/// points. For points of a few samples each, whose own standard errors
/// are too rough to add up.
pub fn pooled_mean_of_means(points: &[(f64, Aggregate)]) -> Option<Aggregate> {
    let counted: Vec<(f64, f64)> = points
        .iter()
        .filter_map(|(_, a)| Some((a.mean?, a.n as f64)))
        .filter(|(_, n)| *n > 0.0)
        .collect();
    if counted.is_empty() {
        return None;
    }
    let k = counted.len() as f64;
    let mean = counted.iter().map(|(m, _)| m).sum::<f64>() / k;
    let sem = pooled_variance(points)
        .map(|s2| (s2 * counted.iter().map(|(_, n)| 1.0 / n).sum::<f64>()).sqrt() / k);
    Some(Aggregate {
        n: points.iter().map(|(_, a)| a.n).sum(),
        mean: Some(mean),
        sd: None,
        sem,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn agg(mean: f64, sem: f64) -> Aggregate {
        Aggregate {
            n: 20,
            mean: Some(mean),
            sd: Some(sem * 20f64.sqrt()),
            sem: Some(sem),
        }
    }

    fn pts(rows: &[(f64, f64, f64)]) -> Vec<(f64, Aggregate)> {
        rows.iter()
            .map(|&(x, mean, sd)| {
                let a = Aggregate {
                    n: 2,
                    mean: Some(mean),
                    sd: Some(sd),
                    sem: Some(sd / 2f64.sqrt()),
                };
                (x, a)
            })
            .collect()
    }

    #[test]
    fn a_pooled_slope_is_the_least_squares_line_with_the_larger_error() {
        // On a line y = 1 + 2x, the means leave no residual: the error is
        // the pooled scatter within, sd / sqrt(Σ n (x − x̄)²) = 0.5 / sqrt(2·2) (x̄ = 1).
        let (b, se) =
            pooled_slope(&pts(&[(0.0, 1.0, 0.5), (1.0, 3.0, 0.5), (2.0, 5.0, 0.5)])).unwrap();
        assert!(
            (b - 2.0).abs() < 1e-12 && (se - 0.25).abs() < 1e-12,
            "{b} {se}"
        );
        // Means off the line, scattered far more than within: y = 1, 4, 5
        // gives slope 2, intercept 4/3, residuals −1/3, 2/3, −1/3, so
        // Σ n r² = 4/3 over 1 degree of freedom and Σ n (x − x̄)² = 4:
        // se = sqrt(1/3), well above the within error 0.1 / 2.
        let (b, se) =
            pooled_slope(&pts(&[(0.0, 1.0, 0.1), (1.0, 4.0, 0.1), (2.0, 5.0, 0.1)])).unwrap();
        assert!((b - 2.0).abs() < 1e-12, "{b}");
        assert!((se - (1.0f64 / 3.0).sqrt()).abs() < 1e-12, "{se}");
        // One point whose two samples happen to agree does not pin the line,
        // as 1/sem² weights let it.
        // Weighted, the line runs through the two tight points (slope 0.25);
        // pooled, it is the least-squares line of the four (1.75 / 5).
        let data = pts(&[
            (0.0, 10.0, 0.5),
            (1.0, 10.0, 1e-4),
            (2.0, 12.0, 0.5),
            (3.0, 10.5, 1e-4),
        ]);
        let (weighted, _) = weighted_slope(&data).unwrap();
        let (pooled, _) = pooled_slope(&data).unwrap();
        assert!((weighted - 0.25).abs() < 1e-3, "{weighted}");
        assert!((pooled - 0.35).abs() < 1e-12, "{pooled}");
        assert_eq!(pooled_slope(&data[..1]), None);
    }

    #[test]
    fn a_value_within_two_combined_errors_agrees() {
        let c = Comparison::quoted("θ".into(), (10.0, 1.0, 25.0), Some(agg(10.3, 0.1)), "why");
        // se = sqrt(0.01 + 0.04) = 0.224; 0.3 / 0.224 = 1.34
        assert_eq!(c.verdict, "agrees");
        assert!((c.sigma.unwrap() - 1.3416).abs() < 1e-3);
        let c = Comparison::quoted("θ".into(), (10.0, 1.0, 25.0), Some(agg(11.0, 0.1)), "why");
        assert_eq!((c.verdict.as_str(), c.reason.as_str()), ("differs", "why"));
        let c = Comparison::quoted("θ".into(), (10.0, 1.0, 25.0), None, "why");
        assert_eq!(c.verdict, "no result");
    }

    #[test]
    fn the_slope_of_points_on_a_line_is_recovered() {
        let pts: Vec<(f64, Aggregate)> = (0..5)
            .map(|k| (k as f64, agg(2.0 + 0.5 * k as f64, 0.1)))
            .collect();
        let (slope, se) = weighted_slope(&pts).unwrap();
        assert!((slope - 0.5).abs() < 1e-12);
        assert!(se > 0.0 && se < 0.1);
    }

    #[test]
    fn a_mean_of_means_takes_its_error_from_the_pooled_scatter() {
        // Three levels of two samples: sd 0.1, 0.5 and 0.9 pool to
        // s² = (0.01 + 0.25 + 0.81) / 3.
        let points = pts(&[(0.0, 24.0, 0.1), (1.0, 25.0, 0.5), (2.0, 26.0, 0.9)]);
        let a = pooled_mean_of_means(&points).unwrap();
        assert_eq!(a.n, 6);
        assert!((a.mean.unwrap() - 25.0).abs() < 1e-12);
        let s2: f64 = (0.01 + 0.25 + 0.81) / 3.0;
        let want = (s2 * 1.5).sqrt() / 3.0;
        assert!((a.sem.unwrap() - want).abs() < 1e-12, "{:?}", a.sem);
        // One sample a level: no scatter to pool, so no error is claimed.
        let single: Vec<(f64, Aggregate)> = points
            .iter()
            .map(|(x, a)| {
                (
                    *x,
                    Aggregate {
                        n: 1,
                        sd: None,
                        ..*a
                    },
                )
            })
            .collect();
        assert_eq!(pooled_mean_of_means(&single).unwrap().sem, None);
    }
}
