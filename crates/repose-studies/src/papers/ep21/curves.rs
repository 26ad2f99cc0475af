//! The curves Elekes & Parteli fit to their heaps and packings, and the
//! constants they quote (eqs. 1–5 and fig. 5 of the paper). Lengths in µm,
//! angles in degrees, g̃ = g / 9.81 m/s².

use crate::fit::Model;

/// μ_∞ and D of eq. 1 on Earth; D at every gravity level is fitted with
/// this μ_∞ held.
pub const MU_INF: f64 = 0.447;
pub const D_EARTH_UM: f64 = 87.0;
/// Eq. 2 fitted freely: D = D₀ g̃^(−α).
pub const D0_UM: f64 = 76.0;
pub const ALPHA: f64 = 0.454;
/// Eq. 4.
pub const MU_INF_BOND: f64 = 0.458;
pub const BETA: f64 = 0.014;
/// The packing fit.
pub const PHI_INF: f64 = 0.57;
pub const PHI_C: f64 = 0.56;
pub const D_PHI_UM: f64 = 103.0;

/// Eq. 1: θ_r(d) = atan(μ_∞ (1 + D/d)), d in µm.
pub static EQ1: Model = Model {
    name: "eq. 1",
    params: &["mu_inf", "D_um"],
    f: |d, p| (p[0] * (1.0 + p[1] / d)).atan().to_degrees(),
};

/// Eq. 1 with μ_∞ = 0.447 held, as the paper fits each gravity level.
pub static EQ1_HELD: Model = Model {
    name: "eq. 1, μ_∞ held at 0.447",
    params: &["D_um"],
    f: |d, p| (MU_INF * (1.0 + p[0] / d)).atan().to_degrees(),
};

/// Eq. 1 with μ_∞ held at a value given to the fit
/// ([`crate::fit::fit_holding`]): D alone is fitted.
pub static EQ1_MU_GIVEN: Model = Model {
    name: "eq. 1, μ_∞ held",
    params: &["D_um"],
    f: |d, p| (p[1] * (1.0 + p[0] / d)).atan().to_degrees(),
};

/// Eq. 2: D(g̃) = D₀ g̃^(−α).
pub static EQ2: Model = Model {
    name: "eq. 2",
    params: &["D0_um", "alpha"],
    f: |g, p| p[0] * g.powf(-p[1]),
};

/// Eq. 2 with the exponent held at 1/2: D(g̃) = D_E / √g̃.
pub static EQ2_HALF: Model = Model {
    name: "eq. 2, exponent held at 1/2",
    params: &["D_um"],
    f: |g, p| p[0] / g.sqrt(),
};

/// Eq. 4: θ_r(Bo) = atan(μ_∞ (1 + β √Bo)).
pub static EQ4: Model = Model {
    name: "eq. 4",
    params: &["mu_inf", "beta"],
    f: |bo, p| (p[0] * (1.0 + p[1] * bo.sqrt())).atan().to_degrees(),
};

/// The packing fit: φ(x) = φ_∞ (1 − C exp(−x / D_φ)), x = d √g̃ in µm.
pub static PACKING: Model = Model {
    name: "packing fit",
    params: &["phi_inf", "C", "D_phi_um"],
    f: |x, p| p[0] * (1.0 - p[1] * (-x / p[2]).exp()),
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::{fit, Datum};

    /// Points of a curve at `xs` with a small, fixed, zero-mean wobble.
    fn points(model: &Model, p: &[f64], xs: &[f64], wobble: f64) -> Vec<Datum> {
        xs.iter()
            .enumerate()
            .map(|(k, &x)| Datum {
                x,
                y: (model.f)(x, p) + wobble * if k % 2 == 0 { 1.0 } else { -1.0 },
                sigma: None,
            })
            .collect()
    }

    fn close(got: f64, want: f64, rel: f64) -> bool {
        (got - want).abs() <= rel * want.abs()
    }

    #[test]
    fn the_papers_curves_give_back_their_constants() {
        let sizes = [10.0, 20.0, 35.0, 50.0, 75.0, 100.0, 200.0, 500.0, 1000.0];
        let f = fit(
            &EQ1,
            &points(&EQ1, &[MU_INF, D_EARTH_UM], &sizes, 0.2),
            &[0.5, 50.0],
        )
        .unwrap();
        assert!(
            close(f.param("mu_inf").unwrap().value, MU_INF, 0.02),
            "{f:?}"
        );
        assert!(
            close(f.param("D_um").unwrap().value, D_EARTH_UM, 0.05),
            "{f:?}"
        );
        let held = fit(
            &EQ1_HELD,
            &points(&EQ1_HELD, &[D_EARTH_UM], &sizes, 0.0),
            &[30.0],
        )
        .unwrap();
        assert!(close(held.params[0].value, D_EARTH_UM, 1e-6), "{held:?}");
        // μ_∞ held at another value: D of data made with it.
        let given = crate::fit::fit_holding(
            &EQ1_MU_GIVEN,
            &points(&EQ1, &[0.5, 120.0], &sizes, 0.0),
            &[30.0],
            &[0.5],
        )
        .unwrap();
        assert!(close(given.params[0].value, 120.0, 1e-6), "{given:?}");
        assert_eq!(given.dof, sizes.len() - 1);

        let gravities = [0.063, 0.165, 0.378, 1.0, 10.0, 100.0];
        let f = fit(
            &EQ2,
            &points(&EQ2, &[D0_UM, ALPHA], &gravities, 0.5),
            &[50.0, 0.3],
        )
        .unwrap();
        let alpha = f.param("alpha").unwrap();
        assert!(alpha.lo < ALPHA && ALPHA < alpha.hi, "{alpha:?}");
        let half = fit(
            &EQ2_HALF,
            &points(&EQ2_HALF, &[D_EARTH_UM], &gravities, 0.0),
            &[10.0],
        )
        .unwrap();
        assert!(close(half.params[0].value, D_EARTH_UM, 1e-6));

        let bonds = [0.1, 1.0, 10.0, 100.0, 1e3, 1e4, 1e5];
        let f = fit(
            &EQ4,
            &points(&EQ4, &[MU_INF_BOND, BETA], &bonds, 0.1),
            &[0.4, 0.05],
        )
        .unwrap();
        assert!(close(f.param("beta").unwrap().value, BETA, 0.05), "{f:?}");

        let x = [20.0, 40.0, 60.0, 100.0, 150.0, 210.0, 400.0, 800.0, 2000.0];
        let truth = [PHI_INF, PHI_C, D_PHI_UM];
        let f = fit(
            &PACKING,
            &points(&PACKING, &truth, &x, 0.002),
            &[0.6, 0.4, 60.0],
        )
        .unwrap();
        for (p, want) in f.params.iter().zip(truth) {
            assert!(p.lo < want && want < p.hi, "{p:?}");
        }
        assert!(f.r2 > 0.99);
    }
}
