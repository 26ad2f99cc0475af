//! Files a run can write: an SVG of the pile with force chains (the paper's
//! fig. 1a), a CSV of the kinetic-energy trace (fig. 1b) and a legacy VTK
//! file for ParaView. In 3D the snapshot is the two side views (`side_views`).

use repose_physics::protocols::pile::BoxSpec;
use repose_physics::RunReport;
use std::collections::HashMap;
use std::fmt::Write;

/// A coordinate of a listed vector (0 past its end).
fn at(v: &[f64], k: usize) -> f64 {
    v.get(k).copied().unwrap_or(0.0)
}

/// The final pile: discs (spheres seen from the side in 3D), lines between
/// touching centres with a width proportional to the normal force, the
/// walls, and the measured surface.
pub fn snapshot_svg(r: &RunReport) -> String {
    if r.dimension == 3 {
        return crate::side_views::svg(r);
    }
    let Some(state) = &r.final_state else {
        return String::new();
    };
    let up = r.dimension.max(1) - 1;
    let (width, height) = r
        .scene
        .section::<BoxSpec>()
        .map_or((0.0, 0.0), |b| (b.width, b.height));
    let grains = &state.grains;
    let (mut xmin, mut xmax, mut ymax) = (0.0f64, width, 0.0f64);
    for g in grains {
        xmin = xmin.min(at(&g.position, 0) - g.radius);
        xmax = xmax.max(at(&g.position, 0) + g.radius);
        ymax = ymax.max(at(&g.position, up) + g.radius);
    }
    let ymin = -0.1;
    ymax = ymax.max(height) + 0.1;
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
        r.protocol,
        r.seed,
        grains.len()
    );
    let view = View {
        px: &px,
        py: &py,
        xmin,
        xmax,
        ymin,
        ymax,
        up,
    };
    s.push_str(&walls_svg(r, &view));
    for g in grains {
        let _ = writeln!(
            s,
            r##"<circle cx="{:.2}" cy="{:.2}" r="{:.2}" fill="#e8dcc0" stroke="#b8a57a" stroke-width="0.6"/>"##,
            px(at(&g.position, 0)),
            py(at(&g.position, up)),
            g.radius * scale
        );
    }
    s.push_str(&chains_svg(r, &view));
    if let (Some(surface), Some(angle)) = (r.profiles.first(), r.metric("theta_r")) {
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
            angle
        );
    }
    s.push_str("</svg>\n");
    s
}

/// Kinetic energy per grain against iteration, in the model's units.
pub fn trace_csv(r: &RunReport) -> String {
    let units = repose_physics::registry::find_model(&r.model)
        .map_or(repose_engine::simulation::Units::CGS, |m| m.units());
    let mut s = format!(
        "iteration,time_s,kinetic_energy_per_grain_{},max_speed_{},phase\n",
        units.energy,
        units.speed.replace('/', "_")
    );
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

/// Legacy VTK polydata: one point per grain with radius, id, velocity and
/// (for rotating grains) angular velocity; 2D grains lie in the plane z = 0.
pub fn vtk(r: &RunReport) -> String {
    let Some(state) = &r.final_state else {
        return String::new();
    };
    let g = &state.grains;
    let xyz = |v: &[f64]| format!("{} {} {}", at(v, 0), at(v, 1), at(v, 2));
    let mut s = String::new();
    let _ = writeln!(s, "# vtk DataFile Version 3.0");
    let _ = writeln!(s, "repose {} seed {}", r.protocol, r.seed);
    let _ = writeln!(s, "ASCII\nDATASET POLYDATA\nPOINTS {} double", g.len());
    for p in g {
        let _ = writeln!(s, "{}", xyz(&p.position));
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
        let _ = writeln!(s, "{}", xyz(&p.velocity));
    }
    if g.iter().any(|p| !p.angular_velocity.is_empty()) {
        let _ = writeln!(s, "VECTORS angular_velocity double");
        for p in g {
            // A 2D grain turns about z.
            let w = match p.angular_velocity.as_slice() {
                [z] => format!("0 0 {z}"),
                v => xyz(v),
            };
            let _ = writeln!(s, "{w}");
        }
    }
    s
}

/// The drawn plane: the map from the first and last axes to the page.
struct View<'a> {
    px: &'a dyn Fn(f64) -> f64,
    py: &'a dyn Fn(f64) -> f64,
    xmin: f64,
    xmax: f64,
    ymin: f64,
    ymax: f64,
    up: usize,
}

/// The walls, seen edge-on: those whose normal lies in the drawn plane.
fn walls_svg(r: &RunReport, v: &View) -> String {
    let Some(state) = &r.final_state else {
        return String::new();
    };
    let mut s = String::new();
    for wall in &state.walls {
        let (nx, ny) = (at(&wall.normal, 0), at(&wall.normal, v.up));
        if r.dimension == 3 && at(&wall.normal, 1).abs() > 1e-9 {
            continue;
        }
        let p = nalgebra::Vector2::new(at(&wall.point, 0), at(&wall.point, v.up));
        let t = nalgebra::Vector2::new(ny, -nx).normalize();
        let far = 1e3;
        let (mut a, mut b) = (p - t * far, p + t * far);
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
            (v.px)(clip(a.x, v.xmin, v.xmax)),
            (v.py)(clip(a.y, v.ymin, v.ymax)),
            (v.px)(clip(b.x, v.xmin, v.xmax)),
            (v.py)(clip(b.y, v.ymin, v.ymax))
        );
    }
    s
}

/// Lines between touching centres, as wide as their normal force.
fn chains_svg(r: &RunReport, v: &View) -> String {
    let Some(state) = &r.final_state else {
        return String::new();
    };
    let grains = &state.grains;
    let mut s = String::new();
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
                (v.px)(at(&ga.position, 0)),
                (v.py)(at(&ga.position, v.up)),
                (v.px)(at(&gb.position, 0)),
                (v.py)(at(&gb.position, v.up)),
                0.3 + 5.0 * c.force / fmax
            );
        }
    }
    s
}
