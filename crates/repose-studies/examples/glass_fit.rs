//! The second paper's fits, made with the study's own fit code on exported
//! samples of the glass-stiff reference runs (`repose export <sweep> --what
//! samples`, the CSVs of `data/glass/`):
//!
//! * `packing FILE...`: φ = φ_∞ (1 − C exp(−d√g̃ / D_φ)) over every column
//!   that settled, each a point at `d√g̃` (µm) from its grain size and
//!   gravity (Earth's where the sweep has no gravity axis);
//! * `eq1 D_UM=FILE...`: eq. 1, θ_r = atan(μ_∞ (1 + D/d)), both constants
//!   free, over every heap that completed, on Earth. A heap sweep keeps its
//!   grain size in its base scene, not on an axis, so each file is named
//!   with its diameter in µm. `--where AXIS=VALUE` keeps the rows whose
//!   axis has that value (a file without the axis is kept whole), and
//!   `--metric NAME` fits another angle than `theta_r`.
//!
//! ```text
//! cargo run --release -p repose-studies --example glass_fit -- packing \
//!     data/glass/packing-earth.csv data/glass/packing-gravity.csv
//! cargo run --release -p repose-studies --example glass_fit -- eq1 \
//!     1000=data/glass/reduced-net-fading-1mm.csv 500=data/glass/reduced-net-fading-500um.csv \
//!     250=data/glass/reduced-net-fading-250um.csv 100=data/glass/caps-100um.csv \
//!     100=data/glass/reduced-net-fading-100um.csv \
//!     --where material.limit_load=net \
//!     --where material.contact_attraction=fading
//! ```

use repose_studies::fit::{fit, Datum, Model};
use repose_studies::papers::ep21::curves::{
    D_EARTH_UM, D_PHI_UM, EQ1, MU_INF, PACKING, PHI_C, PHI_INF,
};
use repose_studies::papers::ep21::{G_EARTH, QUANTITIES};
use repose_studies::quantity::x_value;
use serde_json::{json, Value};
use std::collections::HashMap;

type Error = Box<dyn std::error::Error>;
/// One exported sample: its columns by name.
type Row = HashMap<String, String>;

const USAGE: &str = "usage: glass_fit packing SAMPLES.csv ... | \
                     glass_fit eq1 D_UM=SAMPLES.csv ... [--where AXIS=VALUE] [--metric NAME]";

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (data, model, start, paper): (_, &Model, &[f64], &[f64]) =
        match args.first().map(String::as_str) {
            Some("packing") => (
                packings(&args[1..])?,
                &PACKING,
                &[0.6, 0.5, 100.0],
                &[PHI_INF, PHI_C, D_PHI_UM],
            ),
            Some("eq1") => (
                heaps(&args[1..])?,
                &EQ1,
                &[0.5, 100.0],
                &[MU_INF, D_EARTH_UM],
            ),
            _ => return Err(USAGE.into()),
        };
    for d in &data {
        println!("{:>10.1} {:>8.4}", d.x, d.y);
    }
    let f = fit(model, &data, start)?;
    println!("{}: {} points, R² = {:.4}", model.name, f.points, f.r2);
    for (p, paper) in f.params.iter().zip(paper) {
        println!(
            "{:<9} {:>9.4} ± {:.4}  95 % [{:.4}, {:.4}]  paper {paper}",
            p.name, p.value, p.se, p.lo, p.hi
        );
    }
    Ok(())
}

/// Every row of one export.
fn rows(file: &str) -> Result<Vec<Row>, Error> {
    let mut reader = csv::Reader::from_path(file).map_err(|e| format!("{file}: {e}"))?;
    let mut out = Vec::new();
    for row in reader.deserialize() {
        out.push(row.map_err(|e| format!("{file}: {e}"))?);
    }
    Ok(out)
}

/// The value of column `name`, parsed as a number.
fn number(row: &Row, name: &str) -> Result<f64, Error> {
    let text = row.get(name).ok_or_else(|| format!("no column `{name}`"))?;
    Ok(text
        .parse()
        .map_err(|e| format!("`{name}` = `{text}`: {e}"))?)
}

/// The settled columns of every file as points `(d√g̃ in µm, φ)`.
fn packings(files: &[String]) -> Result<Vec<Datum>, Error> {
    let mut out = Vec::new();
    for file in files {
        for row in rows(file)? {
            if row.get("outcome").map(String::as_str) != Some("completed") {
                continue;
            }
            // The sample's point, as the study reads it for its own fit.
            let diameter = number(&row, "axis:grains.diameter")?;
            let gravity: Value = match row.get("axis:gravity") {
                Some(v) => serde_json::from_str(v)?,
                None => json!([0.0, 0.0, -G_EARTH]),
            };
            let point = json!({"grains.diameter": diameter, "gravity": gravity});
            let point = point.as_object().expect("an object");
            let x = x_value(point, "ep21.d_sqrt_g_um", &QUANTITIES)
                .ok_or_else(|| format!("{file}: a diameter or gravity that is not a number"))?;
            let y = number(&row, "packing_fraction").map_err(|e| format!("{file}: {e}"))?;
            out.push(Datum { x, y, sigma: None });
        }
    }
    out.sort_by(|a, b| a.x.total_cmp(&b.x));
    Ok(out)
}

/// The completed heaps of every `D_UM=FILE` as points `(d in µm, angle)`.
fn heaps(args: &[String]) -> Result<Vec<Datum>, Error> {
    let mut files = Vec::new();
    let mut wanted = Vec::new();
    let mut metric = "theta_r".to_string();
    let mut args = args.iter();
    while let Some(arg) = args.next() {
        let mut value = || args.next().ok_or_else(|| format!("{arg} needs a value"));
        match arg.as_str() {
            "--where" => {
                let pair = value()?;
                let (axis, v) = pair
                    .split_once('=')
                    .ok_or_else(|| format!("--where {pair}: not AXIS=VALUE"))?;
                wanted.push((format!("axis:{axis}"), v.trim_matches('"').to_string()));
            }
            "--metric" => metric = value()?.clone(),
            named => {
                let (d, file) = named
                    .split_once('=')
                    .ok_or_else(|| format!("{named}: not D_UM=FILE"))?;
                let d: f64 = d.parse().map_err(|e| format!("{named}: {e}"))?;
                files.push((d, file.to_string()));
            }
        }
    }
    let mut out = Vec::new();
    for (d, file) in files {
        for row in rows(&file)? {
            let kept = wanted
                .iter()
                .all(|(axis, v)| row.get(axis).is_none_or(|have| have.trim_matches('"') == v));
            if kept && row.get("outcome").map(String::as_str) == Some("completed") {
                let y = number(&row, &metric).map_err(|e| format!("{file}: {e}"))?;
                out.push(Datum {
                    x: d,
                    y,
                    sigma: None,
                });
            }
        }
    }
    out.sort_by(|a, b| a.x.total_cmp(&b.x));
    Ok(out)
}
