//! Files a run can write: an SVG of the pile with force chains (the paper's
//! fig. 1a), a CSV of the kinetic-energy trace (fig. 1b) and a legacy VTK
//! file for ParaView.

use repose_physics::RunReport;
use std::collections::HashMap;
use std::fmt::Write;

/// The final pile: discs, lines between touching centres with a width
/// proportional to the normal force, the walls, and the measured surface.
pub fn snapshot_svg(r: &RunReport) -> String {
    let Some(state) = &r.final_state else {
        return String::new();
    };
    let width = r.scene.container.width;
    let grains = &state.grains;
    let (mut xmin, mut xmax, mut ymax) = (0.0f64, width, 0.0f64);
    for g in grains {
        xmin = xmin.min(g.position.x - g.radius);
        xmax = xmax.max(g.position.x + g.radius);
        ymax = ymax.max(g.position.y + g.radius);
    }
    let ymin = -0.1;
    ymax = ymax.max(r.scene.container.fill_height()) + 0.1;
    xmin -= 0.1;
    xmax += 0.1;
    let scale = 800.0 / (xmax - xmin).max(1e-9);
    let (w, h) = ((xmax - xmin) * scale, (ymax - ymin) * scale);
    let px = |x: f64| (x - xmin) * scale;
    let py = |y: f64| (ymax - y) * scale;

    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{h:.0}" viewBox="0 0 {w:.1} {h:.1}">"#
    );
    let _ = writeln!(s, r##"<rect width="100%" height="100%" fill="#ffffff"/>"##);
    let _ = writeln!(
        s,
        r##"<title>{} seed {}: {} grains</title>"##,
        r.protocol.name(),
        r.seed,
        grains.len()
    );
    // walls
    for wall in &state.walls {
        let n = wall.normal;
        let t = nalgebra::Vector2::new(n.y, -n.x);
        let far = 1e3;
        let (mut a, mut b) = (wall.point - t * far, wall.point + t * far);
        for l in &wall.limits {
            if l.axis == 0 {
                if let Some(m) = l.min {
                    a.x = a.x.max(m);
                    b.x = b.x.max(m);
                }
                if let Some(m) = l.max {
                    a.x = a.x.min(m);
                    b.x = b.x.min(m);
                }
            }
        }
        let clip = |v: f64, lo: f64, hi: f64| v.clamp(lo, hi);
        let _ = writeln!(
            s,
            r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#333" stroke-width="3"/>"##,
            px(clip(a.x, xmin, xmax)),
            py(clip(a.y, ymin, ymax)),
            px(clip(b.x, xmin, xmax)),
            py(clip(b.y, ymin, ymax))
        );
    }
    for g in grains {
        let _ = writeln!(
            s,
            r##"<circle cx="{:.2}" cy="{:.2}" r="{:.2}" fill="#e8dcc0" stroke="#b8a57a" stroke-width="0.6"/>"##,
            px(g.position.x),
            py(g.position.y),
            g.radius * scale
        );
    }
    let by_id: HashMap<u32, usize> = grains.iter().enumerate().map(|(k, g)| (g.id, k)).collect();
    let fmax = state.contacts.iter().map(|c| c.force).fold(0.0, f64::max);
    if fmax > 0.0 {
        for c in &state.contacts {
            let (Some(&a), Some(&b)) = (by_id.get(&c.a), by_id.get(&c.b)) else {
                continue;
            };
            let (ga, gb) = (&grains[a], &grains[b]);
            let _ = writeln!(
                s,
                r##"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="#202020" stroke-width="{:.2}" stroke-linecap="round"/>"##,
                px(ga.position.x),
                py(ga.position.y),
                px(gb.position.x),
                py(gb.position.y),
                0.3 + 5.0 * c.force / fmax
            );
        }
    }
    if let (Some(surface), Some(angles)) = (&r.surface, r.repose) {
        let pts: Vec<String> = surface
            .x
            .iter()
            .zip(&surface.h)
            .map(|(x, h)| format!("{:.1},{:.1}", px(*x), py(*h)))
            .collect();
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#c0392b" stroke-width="1.5" stroke-dasharray="4 3"/>"##,
            pts.join(" ")
        );
        let _ = writeln!(
            s,
            r##"<text x="{:.0}" y="24" font-family="sans-serif" font-size="18" text-anchor="end" fill="#c0392b">θ_R = {:.1}° (method 3)</text>"##,
            w - 10.0,
            angles.cumulative_fit
        );
    }
    s.push_str("</svg>\n");
    s
}

/// Kinetic energy per grain against iteration.
pub fn trace_csv(r: &RunReport) -> String {
    let mut s =
        String::from("iteration,time_s,kinetic_energy_per_grain_erg,max_speed_cm_s,phase\n");
    for p in &r.energy_trace {
        let _ = writeln!(
            s,
            "{},{:.6},{:.6e},{:.6e},{}",
            p.iteration,
            p.time,
            p.kinetic_energy,
            p.max_speed,
            p.phase.name()
        );
    }
    s
}

/// Legacy VTK polydata: one point per grain with radius, velocity and id.
pub fn vtk(r: &RunReport) -> String {
    let Some(state) = &r.final_state else {
        return String::new();
    };
    let g = &state.grains;
    let mut s = String::new();
    let _ = writeln!(s, "# vtk DataFile Version 3.0");
    let _ = writeln!(s, "repose {} seed {}", r.protocol.name(), r.seed);
    let _ = writeln!(s, "ASCII\nDATASET POLYDATA\nPOINTS {} double", g.len());
    for p in g {
        let _ = writeln!(s, "{} {} 0", p.position.x, p.position.y);
    }
    let _ = writeln!(s, "VERTICES {} {}", g.len(), 2 * g.len());
    for k in 0..g.len() {
        let _ = writeln!(s, "1 {k}");
    }
    let _ = writeln!(s, "POINT_DATA {}", g.len());
    let _ = writeln!(s, "SCALARS radius double 1\nLOOKUP_TABLE default");
    for p in g {
        let _ = writeln!(s, "{}", p.radius);
    }
    let _ = writeln!(s, "SCALARS id int 1\nLOOKUP_TABLE default");
    for p in g {
        let _ = writeln!(s, "{}", p.id);
    }
    let _ = writeln!(s, "VECTORS velocity double");
    for p in g {
        let _ = writeln!(s, "{} {} 0", p.velocity.x, p.velocity.y);
    }
    s
}
