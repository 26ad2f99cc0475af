//! Closed-form results: the Hertz contact time, and the angles predicted in
//! section 6 of Lee & Herrmann from the stress-line approximation of
//! Liffman et al.

use std::f64::consts::PI;

/// Duration of an undamped Hertz contact `F = k δ^{3/2}` between bodies of
/// effective mass `m_eff` meeting at speed `v`:
/// `t_c = 2.9432 · δ_max / v` with `δ_max = (5 m_eff v² / 4k)^{2/5}`.
pub fn hertz_contact_time(k: f64, m_eff: f64, v: f64) -> f64 {
    let delta_max = (1.25 * m_eff * v * v / k).powf(0.4);
    HERTZ_TIME_CONSTANT * delta_max / v
}

/// `2 ∫₀¹ dx / √(1 − x^{5/2})`, the dimensionless Hertz contact duration.
pub const HERTZ_TIME_CONSTANT: f64 = 2.943_275_784_8;

/// Angle of marginal stability, eq. (3): `θ_MS = atan(3μ)`, degrees.
pub fn marginal_stability_angle(mu: f64) -> f64 {
    (3.0 * mu).atan().to_degrees()
}

/// The friction coefficient that eq. (4a, 4b) assigns to a tilt `θ_T` of a
/// pile at repose angle `θ_R` (both in degrees).
pub fn eq4_friction(theta_t: f64, theta_r: f64) -> f64 {
    let (t, r) = (theta_t.to_radians(), theta_r.to_radians());
    let (plus, minus) = (PI / 3.0 + t, PI / 3.0 - t);
    let ratio = (plus.tan() + r.tan() * plus.cos()) / (minus.tan() - r.tan() * minus.cos());
    (ratio * minus.cos() - plus.cos()) / (ratio * minus.sin() + plus.sin())
}

/// Tilting angle predicted by eq. (4) for friction `mu` and repose angle
/// `theta_r` (degrees), found by bisection; `None` when no tilt in
/// `[0°, 60° − θ_R)` matches (the friction is below what the pile at rest
/// already uses, or beyond what the approximation can hold).
pub fn tilting_angle(mu: f64, theta_r: f64) -> Option<f64> {
    if !mu.is_finite() || !(0.0..60.0).contains(&theta_r) {
        return None;
    }
    let f = |t: f64| eq4_friction(t, theta_r) - mu;
    // The denominator of (4b) vanishes before 60° − θ_R; stay clear of it.
    let hi_limit = 60.0 - theta_r;
    let mut lo = 0.0;
    if f(lo) > 0.0 {
        return None;
    }
    // Walk up until the sign changes, then bisect.
    let mut hi = lo;
    let step = hi_limit / 200.0;
    loop {
        let next = hi + step;
        if next >= hi_limit {
            return None;
        }
        let v = f(next);
        if !v.is_finite() {
            return None;
        }
        if v >= 0.0 {
            hi = next;
            break;
        }
        lo = next;
        hi = next;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hertz_time_constant_is_the_integral() {
        // 2 ∫ dx/sqrt(1 - x^{5/2}) with x = 1 - u², dx = 2u du to remove the end singularity
        let n = 200_000;
        let mut sum = 0.0;
        for k in 0..n {
            let u = (k as f64 + 0.5) / n as f64;
            let x: f64 = 1.0 - u * u;
            sum += 2.0 * u / (1.0 - x.powf(2.5)).sqrt() / n as f64;
        }
        assert!(
            (2.0 * sum - HERTZ_TIME_CONSTANT).abs() < 1e-6,
            "{}",
            2.0 * sum
        );
    }

    #[test]
    fn marginal_stability_is_atan_three_mu() {
        assert!((marginal_stability_angle(0.2) - 30.963_756_532).abs() < 1e-6);
        assert_eq!(marginal_stability_angle(0.0), 0.0);
    }

    #[test]
    fn eq4_at_zero_tilt_gives_a_sixth_of_the_slope() {
        // At θ_T = 0 eq. (4) reduces to μ = tan θ_R / 6.
        for theta_r in [5.0f64, 18.0, 30.0] {
            let mu = eq4_friction(0.0, theta_r);
            assert!((mu - theta_r.to_radians().tan() / 6.0).abs() < 1e-12);
        }
    }

    #[test]
    fn tilting_angle_solves_eq4_and_falls_with_the_repose_angle() {
        let t18 = tilting_angle(0.2, 18.0).unwrap();
        assert!((eq4_friction(t18, 18.0) - 0.2).abs() < 1e-10);
        let t10 = tilting_angle(0.2, 10.0).unwrap();
        assert!(t10 > t18);
        assert!(t18 > 2.0 && t18 < 6.0, "{t18}");
        // More friction, larger tilt.
        assert!(tilting_angle(0.3, 18.0).unwrap() > t18);
        // A pile already past what μ holds has no positive tilt.
        assert_eq!(tilting_angle(0.01, 18.0), None);
    }
}
