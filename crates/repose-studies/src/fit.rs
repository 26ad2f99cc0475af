//! Non-linear least squares with confidence intervals, for the papers'
//! fits. The minimisation is Levenberg–Marquardt (the
//! `levenberg-marquardt` crate on nalgebra); the standard errors come from
//! the covariance `s² (JᵀJ)⁻¹` at the optimum, with `s²` the residual
//! variance (so error bars given as weights set relative, not absolute,
//! scales), and the 95 % intervals from Student's t with `n − p` degrees
//! of freedom.

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, StudentsT};

/// A curve `y = f(x; p)` with named parameters.
#[derive(Debug, Clone, Copy)]
pub struct Model {
    pub name: &'static str,
    pub params: &'static [&'static str],
    pub f: fn(x: f64, p: &[f64]) -> f64,
}

/// One measured point: x, y and (optionally) the error bar of y, used as
/// a relative weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Datum {
    pub x: f64,
    pub y: f64,
    pub sigma: Option<f64>,
}

/// A fitted parameter with its standard error and 95 % interval.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Param {
    pub name: String,
    pub value: f64,
    pub se: f64,
    pub lo: f64,
    pub hi: f64,
}

/// A fit: its parameters, degrees of freedom and goodness.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Fit {
    pub model: String,
    pub params: Vec<Param>,
    pub points: usize,
    /// Points minus parameters.
    pub dof: usize,
    /// Coefficient of determination of the unweighted y.
    pub r2: f64,
    /// The weighted residuals' rms per degree of freedom, s: the errors
    /// are read as relative weights, so the standard errors above are
    /// scaled by it. A standard error divided by it is the fit's design
    /// alone (its points' x and weights), for pooling s over several fits.
    #[serde(skip)]
    pub scale: f64,
}

impl Fit {
    pub fn param(&self, name: &str) -> Option<&Param> {
        self.params.iter().find(|p| p.name == name)
    }
}

/// Why a fit could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FitError {
    #[error("{model}: {points} points cannot fix {params} parameters and their errors")]
    TooFewPoints {
        model: &'static str,
        points: usize,
        params: usize,
    },
    #[error(
        "{model}: the data hold a value that is not finite or an error bar that is not positive"
    )]
    BadData { model: &'static str },
    #[error("{model}: the least-squares search did not converge ({reason})")]
    NoConvergence { model: &'static str, reason: String },
    #[error("{model}: the parameters are not determined by the data (singular covariance)")]
    Singular { model: &'static str },
}

/// The weighted residuals of a model against data, as the crate's problem.
struct Problem<'a> {
    model: &'a Model,
    data: &'a [Datum],
    p: DVector<f64>,
    /// Constants of the model held at given values, after the free ones.
    held: &'a [f64],
}

impl Problem<'_> {
    fn weight(d: &Datum) -> f64 {
        d.sigma.map_or(1.0, |s| 1.0 / s)
    }

    /// The model at `x` with the free parameters `p` and the held ones.
    fn eval(&self, x: f64, p: &[f64]) -> f64 {
        let mut all = [0.0; 8];
        let n = p.len() + self.held.len();
        all[..p.len()].copy_from_slice(p);
        all[p.len()..n].copy_from_slice(self.held);
        (self.model.f)(x, &all[..n])
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, p: &DVector<f64>) {
        self.p.copy_from(p);
    }

    fn params(&self) -> DVector<f64> {
        self.p.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let p = self.p.as_slice();
        let r = DVector::from_iterator(
            self.data.len(),
            self.data
                .iter()
                .map(|d| (self.eval(d.x, p) - d.y) * Self::weight(d)),
        );
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    /// Central differences, each step scaled to its parameter.
    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let (n, m) = (self.data.len(), self.p.len());
        let mut j = DMatrix::zeros(n, m);
        for k in 0..m {
            let h = 1e-6 * self.p[k].abs().max(1e-12);
            let (mut up, mut down) = (self.p.clone(), self.p.clone());
            up[k] += h;
            down[k] -= h;
            for (i, d) in self.data.iter().enumerate() {
                let df = self.eval(d.x, up.as_slice()) - self.eval(d.x, down.as_slice());
                j[(i, k)] = df / (2.0 * h) * Self::weight(d);
            }
        }
        j.iter().all(|v| v.is_finite()).then_some(j)
    }
}

/// Fits `model` to `data` from the starting parameters `start`.
pub fn fit(model: &Model, data: &[Datum], start: &[f64]) -> Result<Fit, FitError> {
    fit_holding(model, data, start, &[])
}

/// Fits the parameters `model` names to `data` from `start`, its further
/// constants held at `held` (the model's function reads them after the
/// named ones; at most eight in all).
pub fn fit_holding(
    model: &Model,
    data: &[Datum],
    start: &[f64],
    held: &[f64],
) -> Result<Fit, FitError> {
    let (n, m) = (data.len(), model.params.len());
    if n <= m {
        return Err(FitError::TooFewPoints {
            model: model.name,
            points: n,
            params: m,
        });
    }
    let finite = data.iter().all(|d| {
        d.x.is_finite() && d.y.is_finite() && d.sigma.is_none_or(|s| s.is_finite() && s > 0.0)
    });
    if !finite || start.len() != m || m + held.len() > 8 {
        return Err(FitError::BadData { model: model.name });
    }
    let problem = Problem {
        model,
        data,
        p: DVector::from_column_slice(start),
        held,
    };
    let (problem, report) = LevenbergMarquardt::new().minimize(problem);
    if !report.termination.was_successful() {
        return Err(FitError::NoConvergence {
            model: model.name,
            reason: format!("{:?}", report.termination),
        });
    }
    let (r, j) = problem
        .residuals()
        .zip(problem.jacobian())
        .ok_or(FitError::Singular { model: model.name })?;
    let dof = n - m;
    let s2 = r.norm_squared() / dof as f64;
    let cov = (j.transpose() * &j)
        .try_inverse()
        .ok_or(FitError::Singular { model: model.name })?
        * s2;
    let t = StudentsT::new(0.0, 1.0, dof as f64)
        .map(|d| d.inverse_cdf(0.975))
        .map_err(|_| FitError::Singular { model: model.name })?;
    let params = (0..m)
        .map(|k| {
            let (value, se) = (problem.p[k], cov[(k, k)].max(0.0).sqrt());
            Param {
                name: model.params[k].to_string(),
                value,
                se,
                lo: value - t * se,
                hi: value + t * se,
            }
        })
        .collect();
    Ok(Fit {
        model: model.name.to_string(),
        params,
        points: n,
        dof,
        r2: r_squared(&problem),
        scale: s2.sqrt(),
    })
}

fn r_squared(problem: &Problem) -> f64 {
    let (data, p) = (problem.data, problem.p.as_slice());
    let mean = data.iter().map(|d| d.y).sum::<f64>() / data.len() as f64;
    let total: f64 = data.iter().map(|d| (d.y - mean).powi(2)).sum();
    let residual: f64 = data
        .iter()
        .map(|d| (problem.eval(d.x, p) - d.y).powi(2))
        .sum();
    if total > 0.0 {
        1.0 - residual / total
    } else {
        f64::NAN
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand_chacha::rand_core::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A straight line, `a + b x`, for the fits' tests.
    pub(crate) const LINE: Model = Model {
        name: "line",
        params: &["a", "b"],
        f: |x, p| p[0] + p[1] * x,
    };

    const DECAY: Model = Model {
        name: "decay",
        params: &["amplitude", "rate"],
        f: |x, p| p[0] * (-p[1] * x).exp(),
    };

    fn noise(rng: &mut ChaCha8Rng) -> f64 {
        // A sum of uniforms: near-normal, mean 0, variance 1.
        (0..12)
            .map(|_| rng.next_u64() as f64 / u64::MAX as f64)
            .sum::<f64>()
            - 6.0
    }

    #[test]
    fn a_straight_line_matches_ordinary_least_squares_in_closed_form() {
        let xs = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let ys = [1.1, 2.9, 5.2, 6.8, 9.1, 11.0];
        let data: Vec<Datum> = xs
            .iter()
            .zip(ys)
            .map(|(&x, y)| Datum { x, y, sigma: None })
            .collect();
        let f = fit(&LINE, &data, &[0.0, 1.0]).unwrap();
        // Closed form: slope, intercept and the slope's standard error.
        let n = xs.len() as f64;
        let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
        let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
        let sxy: f64 = xs.iter().zip(ys).map(|(x, y)| (x - mx) * (y - my)).sum();
        let b = sxy / sxx;
        let a = my - b * mx;
        let ssr: f64 = xs
            .iter()
            .zip(ys)
            .map(|(x, y)| (y - a - b * x).powi(2))
            .sum();
        let se_b = (ssr / (n - 2.0) / sxx).sqrt();
        let got = f.param("b").unwrap();
        assert!((got.value - b).abs() < 1e-9 && (f.param("a").unwrap().value - a).abs() < 1e-9);
        assert!((got.se - se_b).abs() < 1e-6 * se_b, "{} {}", got.se, se_b);
        // t(0.975, 4) = 2.7764
        assert!(((got.hi - got.value) / got.se - 2.7764).abs() < 1e-3);
        assert!(f.r2 > 0.99 && f.dof == 4);
        // The residual scale, and the design alone once divided out.
        assert!((f.scale - (ssr / (n - 2.0)).sqrt()).abs() < 1e-9);
        assert!((got.se / f.scale - 1.0 / sxx.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn intervals_cover_the_true_parameters_about_as_often_as_they_claim() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let truth = [2.0, 0.7];
        let mut covered = 0;
        let trials = 400;
        for _ in 0..trials {
            let data: Vec<Datum> = (0..12)
                .map(|k| {
                    let x = 0.25 * k as f64;
                    Datum {
                        x,
                        y: (DECAY.f)(x, &truth) + 0.05 * noise(&mut rng),
                        sigma: None,
                    }
                })
                .collect();
            let f = fit(&DECAY, &data, &[1.0, 1.0]).unwrap();
            let rate = f.param("rate").unwrap();
            covered += usize::from(rate.lo <= truth[1] && truth[1] <= rate.hi);
        }
        let share = covered as f64 / trials as f64;
        assert!((0.91..=0.98).contains(&share), "{share}");
    }

    #[test]
    fn bad_fits_say_why() {
        let two = [
            Datum {
                x: 0.0,
                y: 1.0,
                sigma: None,
            },
            Datum {
                x: 1.0,
                y: 2.0,
                sigma: None,
            },
        ];
        assert!(matches!(
            fit(&LINE, &two, &[0.0, 1.0]),
            Err(FitError::TooFewPoints { .. })
        ));
        let mut three = two.to_vec();
        three.push(Datum {
            x: 2.0,
            y: f64::NAN,
            sigma: None,
        });
        assert!(matches!(
            fit(&LINE, &three, &[0.0, 1.0]),
            Err(FitError::BadData { .. })
        ));
        three[2] = Datum {
            x: 2.0,
            y: 3.0,
            sigma: Some(0.0),
        };
        assert!(matches!(
            fit(&LINE, &three, &[0.0, 1.0]),
            Err(FitError::BadData { .. })
        ));
        // The same x three times cannot fix a slope.
        let same: Vec<Datum> = (0..3)
            .map(|k| Datum {
                x: 1.0,
                y: k as f64,
                sigma: None,
            })
            .collect();
        assert!(fit(&LINE, &same, &[0.0, 1.0]).is_err());
    }
}
