//! The paper's figures 2–5 and the regime boundary, with its fits made
//! again on our heaps and packings.

use super::curves::{
    ALPHA, BETA, D0_UM, D_EARTH_UM, D_PHI_UM, EQ1, EQ1_HELD, EQ1_MU_GIVEN, EQ2, EQ2_HALF, EQ4,
    MU_INF, MU_INF_BOND, PACKING, PHI_C, PHI_INF,
};
use super::quantities::{
    g_tilde, BOND_REGIME_I, DENSITY, G_EARTH, QUANTITIES, SURFACE_ENERGY, THETA_COLUMNS,
};
use crate::data::SweepData;
use crate::draw::measured;
use crate::figure::{Figure, FitData, Kind, Layer, PlotPoint, SeriesData};
use crate::fit::Datum;
use crate::fitted::{fitted, weights_all_or_none, Along, OWN_ERROR_SAMPLES};
use repose_store::Point;
use serde_json::Value;

const THETA: &[&str] = &["theta_r"];
const THETA_LABEL: &str = "θ_r (°)";
const D: &str = "ep21.d_um";
const G: &str = "ep21.g_tilde";
const D_LABEL: &str = "grain diameter d (µm)";
const REGIME_I: &str = "regime I (Bo > 10⁴): an irregular heap";

pub fn figures() -> Vec<Figure> {
    vec![fig2(), fig3a(), fig3b(), fig3c(), fig4(), fig5(), regime()]
}

fn every(_: &Point) -> bool {
    true
}

fn eq1(d: f64) -> f64 {
    (EQ1.f)(d, &[MU_INF, D_EARTH_UM])
}

/// Bo of a grain of `d_um` µm at g̃.
fn bond_at(d_um: f64, g_tilde: f64) -> f64 {
    let d = d_um * 1e-6;
    12.0 * SURFACE_ENERGY / (d * d * g_tilde * G_EARTH * DENSITY)
}

/// Marks the points in regime I, given each point's Bond number from its
/// x and its series value.
fn flag_regime(series: &mut [SeriesData], bo: impl Fn(f64, Option<&Value>) -> Option<f64>) {
    for s in series {
        let value = s.series_value.clone();
        for p in &mut s.points {
            if bo(p.x, value.as_ref()).is_some_and(|b| b > BOND_REGIME_I) {
                p.flag = Some(REGIME_I.into());
            }
        }
    }
}

/// The sweep's points at Earth's gravity only.
pub(super) fn on_earth(d: &SweepData) -> SweepData {
    let mut earth = d.clone();
    // g̃ is rounded to nine digits, so Earth's reads back as exactly 1.
    earth.points.retain(|p| g_tilde(&p.point) == Some(1.0));
    earth
}

/// Fig. 2: θ_r against d on Earth, eq. 1 fitted with both constants free.
fn earth_heaps(d: &SweepData) -> (Vec<SeriesData>, Vec<FitData>) {
    let earth = on_earth(d);
    let mut series = measured(&earth, (D, None), THETA, "ours, g̃ = 1", &QUANTITIES);
    flag_regime(&mut series, |x, _| Some(bond_at(x, 1.0)));
    let data = Along::means(D, "theta_r", &earth, &QUANTITIES);
    let fit = fitted(
        &EQ1,
        &[0.45, 80.0],
        "eq. 1 fitted",
        None,
        &data,
        true,
        &mut series,
    );
    (series, vec![fit])
}

fn fig2() -> Figure {
    Figure {
        key: "2",
        title: "θ_r against the grain size d on Earth",
        caption: "Cohesive glass heaps on Earth: θ_r against d with eq. 1 fitted to our means (both constants free) and eq. 1 with the paper's constants. Points in regime I (Bo > 10⁴) are marked.",
        x_label: D_LABEL,
        y_label: THETA_LABEL,
        log_x: true,
        layers: vec![
            Layer::Computed {
                sweep: "heaps",
                f: earth_heaps,
            },
            Layer::Curve {
                label: "eq. 1, paper (μ_∞ = 0.447, D = 87 µm)",
                f: |d| Some(eq1(d)),
            },
        ],
    }
}

/// The Bond number of a point plotted at d (µm) in the series of g̃.
fn bond_of_d(x: f64, g: Option<&Value>) -> Option<f64> {
    Some(bond_at(x, g?.as_f64()?))
}

/// The Bond number of a point plotted at Bo.
fn bond_of_bond(x: f64, _: Option<&Value>) -> Option<f64> {
    Some(x)
}

/// A metric of the heaps along `x`, one series per gravity, regime I
/// marked by the Bond number `bo` of each plotted point.
fn heaps_along(
    d: &SweepData,
    x: &'static str,
    y: &'static [&'static str],
    bo: fn(f64, Option<&Value>) -> Option<f64>,
) -> Vec<SeriesData> {
    let mut series = measured(d, (x, Some(G)), y, "g̃", &QUANTITIES);
    flag_regime(&mut series, bo);
    series
}

fn fig3a() -> Figure {
    Figure {
        key: "3a",
        title: "θ_r against d at six gravity levels",
        caption: "Cohesive glass heaps from Pluto's gravity (g̃ = 0.063) to 100 g: θ_r against d, with eq. 1 fitted at each level (μ_∞ held at 0.447, as the paper fits them).",
        x_label: D_LABEL,
        y_label: THETA_LABEL,
        log_x: true,
        layers: vec![
            Layer::Computed {
                sweep: "heaps",
                f: |d| (heaps_along(d, D, THETA, bond_of_d), Vec::new()),
            },
            Layer::Fit {
                sweep: "heaps",
                x: D,
                series: Some(G),
                y: "theta_r",
                model: &EQ1_HELD,
                start: &[80.0],
                label: "eq. 1 (μ_∞ = 0.447)",
                keep: every,
            },
        ],
    }
}

fn fig3b() -> Figure {
    Figure {
        key: "3b",
        title: "θ_r of heaps without cohesion against g",
        caption: "Heaps of 1 mm beads without surface energy: θ_r,nc against g̃. The paper finds about 24°, rising by about 10 % from g̃ = 0.06 to 100.",
        x_label: "gravity g̃ = g / 9.81 m/s²",
        y_label: THETA_LABEL,
        log_x: true,
        layers: vec![
            Layer::Measured {
                sweep: "dry",
                x: G,
                series: None,
                y: THETA,
                label: "ours, no cohesion",
            },
            Layer::Curve {
                label: "paper: θ_r,nc ≈ 24°",
                f: |_| Some(24.0),
            },
        ],
    }
}

/// D fitted at one gravity level, or why it has none.
pub type FittedD = Result<LevelD, String>;

/// D at one gravity level: its value and standard error, and the fit's
/// residual scale and degrees of freedom behind that error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevelD {
    pub value: f64,
    pub se: f64,
    pub scale: f64,
    pub dof: usize,
}

/// D fitted at each gravity level (eq. 1, μ_∞ held at `mu`), with its
/// standard error: the data of fig. 3C, where `mu` is the paper's 0.447.
pub fn d_by_gravity(d: &SweepData, angle: &str, mu: f64) -> Vec<(f64, FittedD)> {
    let along = Along {
        x: D,
        by: Some(G),
        y: angle,
        keep: every,
        quantities: &QUANTITIES,
    };
    along
        .groups(d)
        .into_iter()
        .filter_map(|(g, data)| {
            let g = g?.as_f64()?;
            let fit = crate::fit::fit_holding(&EQ1_MU_GIVEN, &data, &[80.0], &[mu])
                .map(|f| LevelD {
                    value: f.params[0].value,
                    se: f.params[0].se,
                    scale: f.scale,
                    dof: f.dof,
                })
                .map_err(|e| e.to_string());
            Some((g, fit))
        })
        .collect()
}

/// The fitted D against g̃, weighted by their standard errors: what eq. 2
/// is fitted to, on the figure and in the comparison alike. A level's
/// error is its fit's design (how many sizes, where, how many samples)
/// times that fit's residual scale, which rests on the fit's few degrees
/// of freedom; as with a point's own standard error ([`weigh`](crate::fitted::weigh)), each
/// level's own scale is used only where every level's fit has at least
/// [`OWN_ERROR_SAMPLES`] − 1 degrees of freedom. Otherwise the levels share
/// one scale, and the design alone weighs them.
pub fn d_data(found: &[(f64, FittedD)]) -> Vec<Datum> {
    let levels: Vec<(f64, LevelD)> = found
        .iter()
        .filter_map(|(g, f)| Some((*g, *f.as_ref().ok()?)))
        .collect();
    let usable = |l: &LevelD| l.se > 0.0 && l.scale > 0.0;
    let own = levels
        .iter()
        .all(|(_, l)| usable(l) && l.dof as i64 + 1 >= OWN_ERROR_SAMPLES);
    let mut data: Vec<Datum> = levels
        .iter()
        .map(|(g, l)| Datum {
            x: *g,
            y: l.value,
            sigma: usable(l).then(|| if own { l.se } else { l.se / l.scale }),
        })
        .collect();
    weights_all_or_none(&mut data);
    data
}

/// Fig. 3C: D against g̃ with eq. 2 fitted free and with the exponent ½.
fn d_against_g(d: &SweepData) -> (Vec<SeriesData>, Vec<FitData>) {
    let found = d_by_gravity(d, THETA_COLUMNS, MU_INF);
    let points: Vec<PlotPoint> = found
        .iter()
        .filter_map(|(g, f)| {
            let l = f.as_ref().ok()?;
            Some(PlotPoint {
                sem: Some(l.se),
                sd: Some(l.se),
                ..PlotPoint::value(*g, l.value)
            })
        })
        .collect();
    let data = d_data(&found);
    let mut series = vec![SeriesData {
        name: "D fitted at each g̃ (eq. 1, μ_∞ = 0.447)".into(),
        kind: Kind::Measured,
        series_value: None,
        points,
        band: None,
    }];
    let free = fitted(
        &EQ2,
        &[80.0, 0.5],
        "eq. 2 fitted",
        None,
        &data,
        true,
        &mut series,
    );
    let half = fitted(
        &EQ2_HALF,
        &[80.0],
        "eq. 2 fitted, exponent ½",
        None,
        &data,
        true,
        &mut series,
    );
    (series, vec![free, half])
}

fn fig3c() -> Figure {
    Figure {
        key: "3c",
        title: "the length D of eq. 1 against g",
        caption: "D fitted at each gravity level against g̃, with eq. 2 fitted (prefactor and exponent free, and exponent held at ½) and the paper's D = 87 µm / √g̃.",
        x_label: "gravity g̃ = g / 9.81 m/s²",
        y_label: "D (µm)",
        log_x: true,
        layers: vec![
            Layer::Computed {
                sweep: "heaps",
                f: d_against_g,
            },
            Layer::Curve {
                label: "eq. 2, paper (D₀ = 76 µm, exponent 0.454)",
                f: |g| Some((EQ2.f)(g, &[D0_UM, ALPHA])),
            },
        ],
    }
}

fn fig4() -> Figure {
    Figure {
        key: "4",
        title: "θ_r against the Bond number",
        caption: "Every cohesive heap against Bo = 12γ/(d²gρ) (the paper's factor 12), with eq. 4 fitted to our means and with the paper's constants. Regime I (Bo > 10⁴) marked.",
        x_label: "Bond number Bo",
        y_label: THETA_LABEL,
        log_x: true,
        layers: vec![
            Layer::Computed {
                sweep: "heaps",
                f: |d| (heaps_along(d, "ep21.bond", THETA, bond_of_bond), Vec::new()),
            },
            Layer::Fit {
                sweep: "heaps",
                x: "ep21.bond",
                series: None,
                y: "theta_r",
                model: &EQ4,
                start: &[0.45, 0.02],
                label: "eq. 4 fitted",
                keep: every,
            },
            Layer::Curve {
                label: "eq. 4, paper (μ_∞ = 0.458, β = 0.014)",
                f: |bo| Some((EQ4.f)(bo, &[MU_INF_BOND, BETA])),
            },
        ],
    }
}

fn fig5() -> Figure {
    Figure {
        key: "5",
        title: "packing fraction against d√g̃",
        caption: "Packing fraction of the poured columns against d√g̃ with the paper's exponential fitted to our values and with its constants.",
        x_label: "d √g̃ (µm)",
        y_label: "packing fraction φ",
        log_x: true,
        layers: vec![
            Layer::Measured {
                sweep: "packing",
                x: "ep21.d_sqrt_g_um",
                series: None,
                y: &["packing_fraction"],
                label: "ours",
            },
            Layer::Fit {
                sweep: "packing",
                x: "ep21.d_sqrt_g_um",
                series: None,
                y: "packing_fraction",
                model: &PACKING,
                start: &[0.6, 0.5, 100.0],
                label: "packing fit",
                keep: every,
            },
            Layer::Curve {
                label: "paper (φ_∞ = 0.57, C = 0.56, D_φ = 103 µm)",
                f: |x| Some((PACKING.f)(x, &[PHI_INF, PHI_C, D_PHI_UM])),
            },
        ],
    }
}

fn regime() -> Figure {
    Figure {
        key: "regime",
        title: "irregularity of the heaps against d and g",
        caption: "The rms distance of the heaps' outlines from their fitted triangles against d, one series per g̃. The paper sees irregular heaps below d_c ≈ 50 µm/√g̃ (Bo ≈ 10⁴), and no heap below about d_c/2; points with Bo > 10⁴ are marked, and points where no heap formed count as failures.",
        x_label: D_LABEL,
        y_label: "surface roughness (d)",
        log_x: true,
        layers: vec![Layer::Computed {
            sweep: "heaps",
            f: |d| {
                let s = heaps_along(d, D, &["surface_roughness"], bond_of_d);
                (s, Vec::new())
            },
        }],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(value: f64, se: f64, scale: f64, dof: usize) -> (f64, FittedD) {
        let g = value / 10.0;
        (
            g,
            Ok(LevelD {
                value,
                se,
                scale,
                dof,
            }),
        )
    }

    #[test]
    fn levels_of_few_degrees_of_freedom_share_one_residual_scale() {
        // Two levels of the same design (the same error per unit scale);
        // the second's few sizes happened to lie close to its curve.
        let few = [level(100.0, 4.0, 2.0, 3), level(200.0, 0.2, 0.1, 3)];
        let data = d_data(&few);
        let ratio = data[0].sigma.unwrap() / data[1].sigma.unwrap();
        assert!((ratio - 1.0).abs() < 1e-12, "{ratio}");
        // With nine degrees of freedom each, each level's own error weighs it.
        let many = [level(100.0, 4.0, 2.0, 9), level(200.0, 0.2, 0.1, 9)];
        let data = d_data(&many);
        assert_eq!(data[0].sigma, Some(4.0));
        assert_eq!(data[1].sigma, Some(0.2));
    }

    #[test]
    fn a_level_without_an_error_leaves_every_level_unweighted() {
        let data = d_data(&[
            level(100.0, 4.0, 2.0, 3),
            level(200.0, 0.0, 0.0, 3),
            (5.0, Err("too few sizes".into())),
        ]);
        assert_eq!(data.len(), 2);
        assert!(data.iter().all(|d| d.sigma.is_none()));
    }
}
