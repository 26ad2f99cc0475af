//! The snapshot of a 3D run: its two side views (x–z and y–z) next to each
//! other, every sphere drawn as its disc, with the outline of the heap in
//! each view and the triangles its angles of repose stand for.

use repose_physics::protocols::heap::HeapSpec;
use repose_physics::RunReport;
use serde_json::Value;
use std::fmt::Write;

/// Pixels of one view's width.
const VIEW: f64 = 480.0;

/// A 3D run seen from −y (left) and from +x (right).
pub fn svg(r: &RunReport) -> String {
    let Some(state) = &r.final_state else {
        return String::new();
    };
    let grains = &state.grains;
    let at = |v: &[f64], k: usize| v.get(k).copied().unwrap_or(0.0);
    let largest = grains
        .iter()
        .map(|g| g.radius)
        .fold(0.0, f64::max)
        .max(1e-12);
    let half_plate = r.scene.section::<HeapSpec>().map_or(0.0, |h| h.plate) * 0.5 * 2.0 * largest;
    let mut span = half_plate;
    let mut top = 0.0f64;
    for g in grains {
        for k in 0..2 {
            span = span.max(at(&g.position, k).abs() + g.radius);
        }
        top = top.max(at(&g.position, 2) + g.radius);
    }
    let span = span + largest;
    let top = top + 4.0 * largest;
    let scale = VIEW / (2.0 * span);
    let height = top * scale + 40.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{height:.0}" viewBox="0 0 {w:.0} {height:.0}" font-family="sans-serif">"#,
        w = 2.0 * VIEW + 20.0
    );
    let _ = writeln!(s, r##"<rect width="100%" height="100%" fill="#ffffff"/>"##);
    let _ = writeln!(
        s,
        "<title>{} seed {}: {} grains</title>",
        r.protocol,
        r.seed,
        grains.len()
    );
    let views = r.details.get("side_views");
    for (k, (axis, name)) in [(0usize, "xz"), (1usize, "yz")].into_iter().enumerate() {
        let left = k as f64 * (VIEW + 20.0);
        let px = |x: f64| left + (x + span) * scale;
        let py = |z: f64| height - 20.0 - z * scale;
        let _ = writeln!(
            s,
            r##"<line x1="{:.1}" x2="{:.1}" y1="{:.1}" y2="{:.1}" stroke="#333" stroke-width="2"/>"##,
            px(-half_plate.max(span - largest)),
            px(half_plate.max(span - largest)),
            py(0.0),
            py(0.0)
        );
        for g in grains {
            let _ = writeln!(
                s,
                r##"<circle cx="{:.1}" cy="{:.1}" r="{:.2}" fill="#e8dcc0" stroke="#b8a57a" stroke-width="0.4" fill-opacity="0.8"/>"##,
                px(at(&g.position, axis)),
                py(at(&g.position, 2)),
                g.radius * scale
            );
        }
        if let Some(profile) = r.profiles.get(k) {
            let pts: Vec<String> = profile
                .x
                .iter()
                .zip(&profile.h)
                .map(|(x, h)| format!("{:.1},{:.1}", px(*x), py(*h)))
                .collect();
            let _ = writeln!(
                s,
                r##"<polyline points="{}" fill="none" stroke="#1f5fa8" stroke-width="1.5"/>"##,
                pts.join(" ")
            );
        }
        if let Some(view) = views.and_then(|v| v.get(name)) {
            s.push_str(&triangle(view, 2.0 * largest, half_plate, &px, &py));
        }
    }
    s.push_str("</svg>\n");
    s
}

/// The triangle of the outline's area on the plate (solid) and of the
/// mound above the footprint's height on the footprint (dashed), with the
/// angles.
fn triangle(
    view: &Value,
    d: f64,
    half_plate: f64,
    px: &dyn Fn(f64) -> f64,
    py: &dyn Fn(f64) -> f64,
) -> String {
    let num = |k: &str| view.get(k).and_then(Value::as_f64).unwrap_or(0.0);
    let mut s = String::new();
    for (half, base, theta, dash, label_y) in [
        (half_plate, 0.0, num("theta_plate"), "", 18.0),
        (
            0.5 * num("footprint") * d,
            num("footprint_height") * d,
            num("theta_footprint"),
            r#" stroke-dasharray="5 3""#,
            36.0,
        ),
    ] {
        let apex = base + half * theta.to_radians().tan();
        let _ = writeln!(
            s,
            r##"<polyline points="{:.1},{:.1} {:.1},{:.1} {:.1},{:.1}" fill="none" stroke="#c0392b" stroke-width="1.5"{dash}/>"##,
            px(-half),
            py(base),
            px(0.0),
            py(apex),
            px(half),
            py(base)
        );
        let _ = writeln!(
            s,
            r##"<text x="{:.0}" y="{label_y}" font-size="14" fill="#c0392b">θ = {theta:.1}°{}</text>"##,
            px(-half).max(px(0.0) - 200.0),
            if dash.is_empty() {
                " (plate)"
            } else {
                " (footprint)"
            }
        );
    }
    s
}
