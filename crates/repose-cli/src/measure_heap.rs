//! `repose measure-heap`: reads a heap poured by another engine (a table of
//! grain centres and radii) exactly as the heap protocol reads its own, so
//! that the two engines' angles are one measurement apart, not two.

use anyhow::{bail, Context};
use repose_engine::dim::Vector;
use repose_physics::protocols::heap::read_heap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct MeasureHeapArgs {
    /// Grains, one a line: `x y z radius` in m, or a LAMMPS/LIGGGHTS text
    /// dump whose ATOMS columns include x, y, z and radius. The plate is
    /// z = 0, centred on x = y = 0.
    grains: PathBuf,
    /// The grain diameter d the lengths are read in, m.
    #[arg(long)]
    diameter: f64,
    /// Side of the square plate, in d.
    #[arg(long)]
    plate: f64,
    /// Print one JSON object of the metrics instead of `name value` lines.
    #[arg(long)]
    json: bool,
}

pub fn run(args: MeasureHeapArgs) -> anyhow::Result<ExitCode> {
    for (field, value) in [("--diameter", args.diameter), ("--plate", args.plate)] {
        if !(value.is_finite() && value > 0.0) {
            bail!("{field}: must be a positive number, got {value}");
        }
    }
    let (pos, radius) = read_grains(&args.grains)?;
    let reading = read_heap(&pos, &radius, args.plate, args.diameter)
        .map_err(|reason| anyhow::anyhow!("{}: {reason}", args.grains.display()))?;
    let text = if args.json {
        let map: serde_json::Map<String, serde_json::Value> = reading
            .metrics
            .iter()
            .map(|(name, value)| (name.to_string(), serde_json::json!(value)))
            .collect();
        format!("{}\n", serde_json::Value::Object(map))
    } else {
        reading
            .metrics
            .iter()
            .map(|(name, value)| format!("{name} {value}\n"))
            .collect()
    };
    crate::emit(&text)?;
    Ok(ExitCode::SUCCESS)
}

/// The grains of a plain `x y z radius` table or of a LAMMPS text dump.
fn read_grains(path: &Path) -> anyhow::Result<(Vec<Vector<3>>, Vec<f64>)> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut columns = [0usize, 1, 2, 3];
    let mut in_atoms = true;
    let (mut pos, mut radius) = (Vec::new(), Vec::new());
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if let Some(header) = line.strip_prefix("ITEM:") {
            in_atoms = dump_columns(header, &mut columns)
                .with_context(|| format!("{}:{}", path.display(), n + 1))?;
            continue;
        }
        if !in_atoms || line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        let value = |c: usize| -> anyhow::Result<f64> {
            let field = fields
                .get(c)
                .with_context(|| format!("{}:{}: no column {}", path.display(), n + 1, c + 1))?;
            let v: f64 = field
                .parse()
                .with_context(|| format!("{}:{}: `{field}` is no number", path.display(), n + 1))?;
            if !v.is_finite() {
                bail!("{}:{}: `{field}` is not finite", path.display(), n + 1);
            }
            Ok(v)
        };
        pos.push(Vector::<3>::new(
            value(columns[0])?,
            value(columns[1])?,
            value(columns[2])?,
        ));
        radius.push(value(columns[3])?);
    }
    if pos.is_empty() {
        bail!("{}: no grains", path.display());
    }
    Ok((pos, radius))
}

/// Reads a dump's `ITEM:` line: for `ATOMS`, where x, y, z and radius stand
/// (true: the lines that follow are grains); any other item is skipped.
fn dump_columns(header: &str, columns: &mut [usize; 4]) -> anyhow::Result<bool> {
    let mut words = header.split_whitespace();
    if words.next() != Some("ATOMS") {
        return Ok(false);
    }
    let names: Vec<&str> = words.collect();
    for (slot, want) in columns.iter_mut().zip(["x", "y", "z", "radius"]) {
        *slot = names
            .iter()
            .position(|n| *n == want)
            .with_context(|| format!("the dump's ATOMS have no `{want}` column"))?;
    }
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(text: &str) -> PathBuf {
        let path = repose_testkit::scratch_dir("measure-heap").join("grains.txt");
        std::fs::write(&path, text).unwrap();
        path
    }

    #[test]
    fn a_dump_and_a_plain_table_give_the_same_grains() {
        let dump = write(
            "ITEM: TIMESTEP\n7\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\n\
             ITEM: ATOMS id radius x y z\n1 0.5 0.1 0.2 0.3\n2 0.25 -1 -2 4\n",
        );
        let table = write("# x y z radius\n0.1 0.2 0.3 0.5\n-1 -2 4 0.25\n");
        let a = read_grains(&dump).unwrap();
        let b = read_grains(&table).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.0[1], Vector::<3>::new(-1.0, -2.0, 4.0));
        assert_eq!(a.1, vec![0.5, 0.25]);
    }

    #[test]
    fn a_bad_line_is_named() {
        let f = write("0 0 0.5 0.5\n0 0 nan 0.5\n");
        let err = read_grains(&f).unwrap_err().to_string();
        assert!(err.contains(":2:"), "{err}");
        let f = write("ITEM: ATOMS id x y z\n1 0 0 0\n");
        let err = format!("{:#}", read_grains(&f).unwrap_err());
        assert!(err.contains("`radius`"), "{err}");
    }
}
