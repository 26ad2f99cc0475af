//! Shared by the physics tests: the independent reference integrator.

/// One classical fourth-order Runge–Kutta step of `x'' = accel(x, x')`
/// with step `h`; returns the new `(x, x')`.
pub fn rk4_step(accel: impl Fn(f64, f64) -> f64, x: f64, v: f64, h: f64) -> (f64, f64) {
    let k1 = (v, accel(x, v));
    let k2 = (
        v + 0.5 * h * k1.1,
        accel(x + 0.5 * h * k1.0, v + 0.5 * h * k1.1),
    );
    let k3 = (
        v + 0.5 * h * k2.1,
        accel(x + 0.5 * h * k2.0, v + 0.5 * h * k2.1),
    );
    let k4 = (v + h * k3.1, accel(x + h * k3.0, v + h * k3.1));
    (
        x + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
        v + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
    )
}
