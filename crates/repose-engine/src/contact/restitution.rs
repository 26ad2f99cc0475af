//! The damping constant `A_n` of [`super::ViscoelasticHertz`] that gives a
//! chosen coefficient of restitution at a reference impact speed.
//!
//! In units of the collision (overlap in `δ₀ = (m_eff v²/k_n)^{2/5}`, time
//! in `δ₀/v`) a head-on collision obeys `δ'' = −√δ (δ + (3/2) a δ')` with
//! `δ(0) = 0`, `δ'(0) = 1`, and its restitution depends on the one number
//! `a = A_n (k_n/m_eff)^{2/5} v^{1/5}` alone. [`solved`] finds the `a` of a
//! restitution by integrating that collision; [`pade`] reads it off the
//! [1/4] Padé approximant of Müller & Pöschel that Elekes & Parteli used,
//! which gives a few per cent less restitution than asked for when the
//! collision is integrated. At a coarse step the integrator itself changes
//! the restitution: [`solved_verlet`] finds the `a` whose collision,
//! stepped as the engine's velocity Verlet steps it, rebounds as asked.

/// The restitution of the collision with damping `a` (units above),
/// integrated with classical Runge–Kutta until the spheres separate.
pub fn restitution(a: f64) -> f64 {
    let accel = |d: f64, v: f64| -> f64 {
        if d <= 0.0 {
            return 0.0;
        }
        -(d.sqrt() * (d + 1.5 * a * v)).max(0.0)
    };
    let h = 1e-4;
    let (mut d, mut v) = (0.0f64, 1.0f64);
    // A collision lasts about 3.2 units undamped; heavy damping stretches it.
    for _ in 0..2_000_000 {
        let (k1d, k1v) = (v, accel(d, v));
        let (k2d, k2v) = (
            v + 0.5 * h * k1v,
            accel(d + 0.5 * h * k1d, v + 0.5 * h * k1v),
        );
        let (k3d, k3v) = (
            v + 0.5 * h * k2v,
            accel(d + 0.5 * h * k2d, v + 0.5 * h * k2v),
        );
        let (k4d, k4v) = (v + h * k3v, accel(d + h * k3d, v + h * k3v));
        let nd = d + h / 6.0 * (k1d + 2.0 * k2d + 2.0 * k3d + k4d);
        let nv = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        if nd <= 0.0 && nv < 0.0 {
            return -nv;
        }
        // Once the floored force is zero while separating, nothing slows the
        // spheres any more: they leave at this speed.
        if nv < 0.0 && nd + 1.5 * a * nv <= 0.0 {
            return -nv;
        }
        (d, v) = (nd, nv);
    }
    0.0
}

/// The damping `a` whose integrated collision has restitution `epsilon`
/// (0 < ε ≤ 1), to a relative 1e-10 in `a`.
pub fn solved(epsilon: f64) -> f64 {
    if epsilon >= 1.0 {
        return 0.0;
    }
    bisect_decreasing(restitution, epsilon)
}

/// The restitution of the collision with damping `a` stepped by velocity
/// Verlet with step `h` (units above; the Hertz collision time is 3.21):
/// half kick, drift, the force from the new overlap and the half-step
/// velocity, half kick, as the engine steps. The mean over
/// [`CONTACT_PHASES`] evenly spread instants of first contact within a step.
pub fn restitution_verlet(a: f64, h: f64) -> f64 {
    let accel = |d: f64, v: f64| -> f64 {
        if d <= 0.0 {
            return 0.0;
        }
        -(d.sqrt() * (d + 1.5 * a * v)).max(0.0)
    };
    let steps = (1000.0 / h).ceil() as usize;
    let one = |phase: f64| {
        let (mut d, mut v, mut f) = (-phase * h, 1.0f64, 0.0f64);
        for _ in 0..steps {
            let half = v + 0.5 * h * f;
            d += h * half;
            f = accel(d, half);
            v = half + 0.5 * h * f;
            if d <= 0.0 && v < 0.0 {
                return -v;
            }
        }
        0.0
    };
    (0..CONTACT_PHASES)
        .map(|k| one((k as f64 + 0.5) / CONTACT_PHASES as f64))
        .sum::<f64>()
        / CONTACT_PHASES as f64
}

/// Instants of first contact within a step that [`restitution_verlet`] averages over.
pub const CONTACT_PHASES: usize = 16;

/// The damping `a` whose collision stepped by velocity Verlet at step `h`
/// (units above) rebounds on average with restitution `epsilon`; at a fine
/// step this is [`solved`].
pub fn solved_verlet(epsilon: f64, h: f64) -> f64 {
    let exact = solved(epsilon);
    if epsilon >= 1.0 {
        return 0.0;
    }
    // Past a few times the exact damping the explicit step makes the damper
    // unstable and the rebound grows again: search below that.
    let f = |a: f64| restitution_verlet(a, h);
    let mut hi = 2.0 * exact;
    while f(hi) > epsilon && hi < 16.0 * exact {
        hi *= 1.5;
    }
    if f(hi) > epsilon {
        return exact;
    }
    bisect_decreasing_in(f, epsilon, 1e-9, hi)
}

/// The damping `a` of the Müller–Pöschel [1/4] Padé form
/// `ε = (1 + c₁x)/(1 + c₁x + c₂x² + c₃x³ + c₄x⁴)`, `x² = (3/2) a`.
pub fn pade(epsilon: f64) -> f64 {
    if epsilon >= 1.0 {
        return 0.0;
    }
    bisect_decreasing(pade_restitution, epsilon)
}

/// The Padé form's restitution at damping `a`.
pub fn pade_restitution(a: f64) -> f64 {
    let x = (1.5 * a).sqrt();
    let (c1, c2, c3, c4) = (0.501086, 1.15345, 0.577977, 0.532178);
    let top = 1.0 + c1 * x;
    top / (top + c2 * x * x + c3 * x * x * x + c4 * x * x * x * x)
}

/// `A_n` (s) for a contact of stiffness `k_n` and effective mass `m_eff`
/// at impact speed `speed` from the dimensionless damping `a`.
pub fn damping_constant(a: f64, k_n: f64, m_eff: f64, speed: f64) -> f64 {
    a * (m_eff / k_n).powf(0.4) * speed.powf(-0.2)
}

/// The `a` at which a decreasing `f` equals `target`, by bisection in log a.
fn bisect_decreasing(f: impl Fn(f64) -> f64, target: f64) -> f64 {
    bisect_decreasing_in(f, target, 1e-9, 1e4)
}

/// The `a` in `[from, to]` at which `f`, decreasing there, equals `target`.
fn bisect_decreasing_in(f: impl Fn(f64) -> f64, target: f64, from: f64, to: f64) -> f64 {
    let (mut lo, mut hi) = (from.ln(), to.ln());
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if f(mid.exp()) > target {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-10 {
            break;
        }
    }
    (0.5 * (lo + hi)).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_damping_gives_an_elastic_collision_and_more_damping_less_bounce() {
        assert!((restitution(0.0) - 1.0).abs() < 1e-9);
        assert!(restitution(0.1) > restitution(0.2));
        let a = solved(0.2);
        assert!((restitution(a) - 0.2).abs() < 1e-8, "{a}");
    }

    #[test]
    fn verlet_at_a_fine_step_is_the_exact_collision_and_at_a_coarse_one_is_solved_for() {
        let a = solved(0.2);
        let fine = restitution_verlet(a, 3.21e-3);
        assert!((fine - 0.2).abs() < 1e-3, "{fine}");
        // At a tenth of the collision time the exact damping rebounds less.
        let coarse = restitution_verlet(a, 0.321);
        assert!(coarse < 0.195, "{coarse}");
        let stepped = solved_verlet(0.2, 0.321);
        assert!((restitution_verlet(stepped, 0.321) - 0.2).abs() < 1e-8);
        assert!(stepped < a);
    }

    #[test]
    fn the_pade_form_undershoots_the_restitution_it_is_asked_for() {
        // Elekes & Parteli: ≈ 0.192 integrated for a target of 0.2, ≈ 0.395 for 0.4.
        let at_02 = restitution(pade(0.2));
        let at_04 = restitution(pade(0.4));
        assert!((at_02 - 0.192).abs() < 0.003, "{at_02}");
        assert!((at_04 - 0.395).abs() < 0.003, "{at_04}");
        assert!((pade_restitution(pade(0.3)) - 0.3).abs() < 1e-9);
    }
}
