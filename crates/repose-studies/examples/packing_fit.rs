//! The second paper's packing fit, `φ = φ_∞ (1 − C exp(−d√g̃ / D_φ))`,
//! made with the study's own fit on exported samples of packed columns
//! (`repose export <sweep> --what samples`): every sample that settled is a
//! point at `d√g̃` (µm) from its grain size and gravity (Earth's where the
//! sweep has no gravity axis).
//!
//! ```text
//! cargo run --release -p repose-studies --example packing_fit -- \
//!     data/glass/packing-earth.csv data/glass/packing-gravity.csv
//! ```

use repose_studies::fit::{fit, Datum};
use repose_studies::papers::ep21::curves::{D_PHI_UM, PACKING, PHI_C, PHI_INF};
use repose_studies::papers::ep21::{G_EARTH, QUANTITIES};
use repose_studies::quantity::x_value;
use serde_json::{json, Value};
use std::collections::HashMap;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let files: Vec<String> = std::env::args().skip(1).collect();
    if files.is_empty() {
        return Err("usage: packing_fit SAMPLES.csv ...".into());
    }
    let mut data = Vec::new();
    for file in &files {
        data.extend(points(file)?);
    }
    data.sort_by(|a, b| a.x.total_cmp(&b.x));
    println!("{:>10} {:>8}", "d√g̃ (µm)", "φ");
    for d in &data {
        println!("{:>10.1} {:>8.4}", d.x, d.y);
    }
    let f = fit(&PACKING, &data, &[0.6, 0.5, 100.0])?;
    println!("{} points, R² = {:.4}", f.points, f.r2);
    for (p, paper) in f.params.iter().zip([PHI_INF, PHI_C, D_PHI_UM]) {
        println!(
            "{:<9} {:>9.4} ± {:.4}  95 % [{:.4}, {:.4}]  paper {paper}",
            p.name, p.value, p.se, p.lo, p.hi
        );
    }
    Ok(())
}

/// The settled samples of one export as points `(d√g̃ in µm, φ)`.
fn points(file: &str) -> Result<Vec<Datum>, Box<dyn std::error::Error>> {
    let mut reader = csv::Reader::from_path(file).map_err(|e| format!("{file}: {e}"))?;
    let mut out = Vec::new();
    for row in reader.deserialize() {
        let row: HashMap<String, String> = row?;
        let field = |name: &str| {
            row.get(name)
                .ok_or_else(|| format!("{file}: no column `{name}`"))
        };
        if field("outcome")? != "completed" {
            continue;
        }
        // The sample's point, as the study reads it for its own fit.
        let diameter: f64 = field("axis:grains.diameter")?.parse()?;
        let gravity: Value = match row.get("axis:gravity") {
            Some(v) => serde_json::from_str(v)?,
            None => json!([0.0, 0.0, -G_EARTH]),
        };
        let point = json!({"grains.diameter": diameter, "gravity": gravity});
        let point = point.as_object().expect("an object");
        let x = x_value(point, "ep21.d_sqrt_g_um", &QUANTITIES)
            .ok_or_else(|| format!("{file}: a diameter or gravity that is not a number"))?;
        out.push(Datum {
            x,
            y: field("packing_fraction")?.parse()?,
            sigma: None,
        });
    }
    Ok(out)
}
