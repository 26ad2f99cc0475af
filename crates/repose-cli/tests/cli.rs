//! The `repose` binary as a user drives it: example scenes, output files,
//! and refusals of bad input with the field named and a non-zero exit.

use std::path::PathBuf;
use std::process::{Command, Output};

fn repose(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_repose"))
        .args(args)
        .current_dir(workspace())
        .output()
        .expect("the repose binary runs")
}

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn every_example_scene_parses() {
    for entry in std::fs::read_dir(workspace().join("examples")).unwrap() {
        let path = entry.unwrap().path();
        let scene = std::fs::read_to_string(&path).unwrap();
        repose_physics::Scene::from_toml(&scene, &[])
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
}

#[test]
fn collision_example_prints_one_json_document_with_the_final_state() {
    let out = repose(&["run", "examples/collision.toml", "--json", "--state"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    assert_eq!(report["outcome"]["status"], "completed");
    assert_eq!(report["rng"], "chacha8");
    assert_eq!(report["options"]["integrator"], "gear5");
    let grains = report["final_state"]["grains"].as_array().unwrap();
    let e = (grains[1]["velocity"][0].as_f64().unwrap()
        - grains[0]["velocity"][0].as_f64().unwrap())
        / 10.0;
    assert!(e > 0.5 && e < 1.0, "restitution {e}");
    // Without --state the grains are left out.
    let out = repose(&["run", "examples/collision.toml", "--json"]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(report.get("final_state").is_none());
}

#[test]
fn a_reader_that_closes_the_pipe_early_ends_the_run_quietly() {
    // As in `repose run … | head -1`: the reader is gone before the report
    // is written, which is no error of the run and no reason to panic.
    closed_pipe(&["run", "examples/collision.toml", "--json", "--state"]);
    // A benchmark's table is written line by line, each line a chance to
    // find the reader gone.
    closed_pipe(&[
        "bench",
        "--sizes",
        "2",
        "--integrators",
        "verlet",
        "--scale",
        "0.01",
    ]);
}

/// Runs `args` with standard output's reader gone from the start and
/// asserts a quiet, successful end.
fn closed_pipe(args: &[&str]) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_repose"))
        .args(args)
        .current_dir(workspace())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the repose binary runs");
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = text(&out.stderr);
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    assert!(out.status.success(), "{args:?}, {:?}: {stderr}", out.status);
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn fill_release_writes_a_snapshot_a_trace_and_a_vtk_file() {
    let dir = repose_testkit::scratch_dir("repose-cli");
    let (svg, csv, vtk) = (
        dir.join("pile.svg"),
        dir.join("ke.csv"),
        dir.join("pile.vtk"),
    );
    let out = repose(&[
        "run",
        "examples/fill_release.toml",
        "--set",
        "box.width=2",
        "--set",
        "box.height=2",
        "--snapshot",
        svg.to_str().unwrap(),
        "--trace",
        csv.to_str().unwrap(),
        "--vtk",
        vtk.to_str().unwrap(),
    ]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    assert!(
        stdout.contains("θ_R") && stdout.contains("(theta_r)"),
        "{stdout}"
    );
    let svg = std::fs::read_to_string(svg).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("<circle") && svg.contains("stroke-width"));
    let csv = std::fs::read_to_string(csv).unwrap();
    let mut lines = csv.lines();
    assert!(lines
        .next()
        .unwrap()
        .starts_with("iteration,time_s,kinetic_energy_per_grain_erg"));
    let phases: Vec<&str> = lines.map(|l| l.rsplit(',').next().unwrap()).collect();
    assert!(phases.contains(&"fill") && phases.contains(&"flow"));
    let vtk = std::fs::read_to_string(vtk).unwrap();
    assert!(vtk.starts_with("# vtk DataFile") && vtk.contains("SCALARS radius"));
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn bad_input_names_the_field_and_exits_non_zero() {
    let cases: &[(&[&str], &str)] = &[
        (&["--set", "contact.mu=-0.2"], "contact.mu"),
        (&["--set", "grains.radius_mean=0"], "grains.radius_mean"),
        (&["--set", "grains.radius_min=-0.1"], "grains.radius_min"),
        (&["--set", "box.width=0.1"], "box.width"),
        (&["--set", "box.grains=5000"], "box.grains"),
        (&["--set", "contact.k_n=nan"], "contact.k_n"),
        (&["--set", "numerics.dt_factor=0"], "numerics.dt_factor"),
        (&["--set", "contact.frobnicate=1"], "contact.frobnicate"),
        (&["--set", "contact.mu=\"high\""], "contact.mu"),
        (&["--set", "mu"], "mu"),
        // A pile is built on its floor: gravity straight down, and not zero.
        (&["--set", "gravity=[0, 0]"], "gravity"),
        (&["--set", "gravity=[100, -981]"], "gravity"),
    ];
    for (extra, field) in cases {
        let mut args = vec!["run", "examples/fill_release.toml"];
        args.extend_from_slice(extra);
        let out = repose(&args);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {stderr}");
        assert!(stderr.contains(field), "{extra:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    let out = repose(&["run", "no/such/scene.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("cannot read scene file"));
    // A scene file may write nan and inf, which must not read as "not set"
    // and so as the default.
    let dir = repose_testkit::scratch_dir("cli-nan");
    for (body, field) in [
        ("[box]\nwidth = nan\n", "box.width"),
        ("gravity = [0.0, -inf]\n", "gravity[1]"),
    ] {
        let file = dir.join("scene.toml");
        std::fs::write(&file, format!("protocol = \"fill_release\"\n{body}")).unwrap();
        let out = repose(&["run", file.to_str().unwrap()]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{body}: {stderr}");
        assert!(stderr.contains(field), "{body}: {stderr}");
    }

    // The studies refuse a bad override before running anything.
    let cases: &[(&[&str], &str)] = &[
        (&["tradeoff", "--seeds", "0"], "--seeds"),
        (&["tradeoff", "--set", "box.wdth=1"], "box.wdth"),
        (&["tradeoff", "--set", "contact.mu=-1"], "contact.mu"),
    ];
    for (args, field) in cases {
        let out = repose(&[args, &["--out", "/nonexistent/sva.md", "-q"][..]].concat());
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(field), "{args:?}: {stderr}");
    }
}

#[test]
fn a_workers_lease_heartbeat_and_checkpoints_are_refused_out_of_range() {
    let dir = repose_testkit::scratch_dir("repose-worker-flags");
    let db = format!("sqlite://{}", dir.join("w.db").display());
    let cases: &[(&[&str], &str)] = &[
        (&["--lease", "inf"], "--lease"),
        (&["--lease", "1e20"], "--lease"),
        (&["--lease=-5"], "--lease"),
        (&["--heartbeat", "1e-10"], "--heartbeat"),
        (&["--heartbeat", "90", "--lease", "60"], "--heartbeat"),
        (&["--checkpoint-every", "1e20"], "--checkpoint-every"),
        (&["--checkpoint-every", "nan"], "--checkpoint-every"),
    ];
    for (extra, flag) in cases {
        let out = repose(
            &[
                &["worker", "--database", &db, "--exit-when-idle"][..],
                extra,
            ]
            .concat(),
        );
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {stderr}");
        assert!(stderr.contains(flag), "{extra:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    // The server's embedded workers take the same flags, checked as early.
    let out = repose(&["serve", "--database", &db, "--lease", "inf"]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("--lease"));
    assert!(
        !dir.join("w.db").exists(),
        "refused before opening the store"
    );
}

#[test]
fn a_worker_on_a_store_no_server_has_made_exits_naming_it() {
    // A mistyped path used to start an empty store that no server fed, and
    // the worker waited on it for ever.
    let dir = repose_testkit::scratch_dir("repose-worker-missing");
    let file = dir.join("mistyped.db");
    let db = format!("sqlite://{}", file.display());
    let out = repose(&["worker", "--database", &db, "--exit-when-idle"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("mistyped.db") && stderr.contains("repose serve"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!file.exists(), "the worker created the store");
}

#[test]
fn a_run_that_fails_says_why_and_exits_with_one() {
    // A forced step twice the contact time is refused before anything runs.
    let out = repose(&[
        "run",
        "examples/collision.toml",
        "--set",
        "numerics.dt=2e-3",
    ]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("numerics.dt") && stderr.contains("stability limit"),
        "{stderr}"
    );

    // Just inside the limit the step is accepted, but half a contact time
    // per step is far too coarse: the energy guard fails the run.
    let out = repose(&[
        "run",
        "examples/collision.toml",
        "--set",
        "numerics.dt=5e-4",
        "--set",
        "duration=0.05",
    ]);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("failed") && stdout.contains("energy blow-up"),
        "{stdout}"
    );
}

/// One row of the tradeoff CSV: setting, seed and the four angles (None when
/// the run gave none).
type Row = (String, u64, [Option<f64>; 4]);

fn tradeoff_rows(csv: &str) -> Vec<Row> {
    assert!(csv.starts_with("setting,group,seed,status"), "{csv}");
    csv::Reader::from_reader(csv.as_bytes())
        .records()
        .map(|r| {
            let f = r.unwrap();
            let angle = |i: usize| f[i].parse::<f64>().ok();
            (
                f[0].to_string(),
                f[2].parse().unwrap(),
                [angle(4), angle(5), angle(6), angle(7)],
            )
        })
        .collect()
}

/// Mean and standard error of one angle over a setting's rows.
fn mean_sem(rows: &[Row], setting: &str, angle: usize) -> (f64, f64, usize) {
    let v: Vec<f64> = rows
        .iter()
        .filter(|r| r.0 == setting)
        .filter_map(|r| r.2[angle])
        .collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt(), v.len())
}

/// "Δ ± se" from a report cell.
fn shift_cell(cell: &str) -> (f64, f64) {
    let (d, se) = cell
        .split_once(" ± ")
        .unwrap_or_else(|| panic!("cell {cell:?}"));
    (d.trim().parse().unwrap(), se.trim().parse().unwrap())
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn tradeoff_reports_the_shift_of_each_preset_from_its_own_samples() {
    let dir = repose_testkit::scratch_dir("repose-tradeoff");
    let out = dir.join("sva.md");
    let args = |extra: &[&'static str]| {
        let mut a = vec![
            "tradeoff",
            "--seeds",
            "3",
            "--only",
            "presets",
            "--set",
            "box.width=1.2",
            "--set",
            "box.height=1.2",
            "-q",
            "--out",
        ];
        a.push(out.to_str().unwrap());
        a.extend_from_slice(extra);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let run = |extra: &[&'static str]| {
        let a = args(extra);
        let out = repose(&a.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(out.status.success(), "{}", text(&out.stderr));
    };
    run(&[]);
    let read = |suffix: &str| std::fs::read_to_string(dir.join(format!("sva{suffix}"))).unwrap();
    let (report, csv) = (read(".md"), read(".csv"));
    for svg in ["-repose.svg", "-tilt.svg"] {
        assert!(read(svg).starts_with("<svg"), "{svg}");
    }

    // Every setting ran every seed.
    let rows = tradeoff_rows(&csv);
    let settings = ["reference", "quick", "standard", "paper"];
    for s in settings {
        let seeds: Vec<u64> = rows.iter().filter(|r| r.0 == s).map(|r| r.1).collect();
        assert_eq!(seeds, [1, 2, 3], "{s}");
    }

    // Each preset's row in the report is its samples' mean less the
    // reference's, with the combined standard error, and its verdict follows
    // the two-standard-error rule.
    for s in &settings[1..] {
        let line = report
            .lines()
            .find(|l| l.starts_with(&format!("| {s} |")))
            .unwrap_or_else(|| panic!("no row for {s} in\n{report}"));
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // | name | what | wall | steps | θ_R | Δθ_R | θ_T | Δθ_T | failed | verdict |
        let mut shifted = [false; 2];
        for (k, (angle, cell)) in [(2usize, cells[6]), (3, cells[8])].into_iter().enumerate() {
            let (m, sem, n) = mean_sem(&rows, s, angle);
            let (m_ref, sem_ref, _) = mean_sem(&rows, "reference", angle);
            assert_eq!(n, 3, "{s}: {line}");
            let (delta, se) = shift_cell(cell);
            assert!(
                (delta - (m - m_ref)).abs() < 0.006,
                "{s}: {cell} against {}",
                m - m_ref
            );
            let se_expected = (sem * sem + sem_ref * sem_ref).sqrt();
            assert!(
                (se - se_expected).abs() < 0.006,
                "{s}: {cell} against ± {se_expected}"
            );
            shifted[k] = delta.abs() > 2.0 * se;
        }
        let verdict = cells[10];
        assert_eq!(verdict.contains("shifts θ_R"), shifted[0], "{line}");
        assert_eq!(verdict.contains("θ_T"), shifted[1], "{line}");
        assert_eq!(
            verdict == "within error",
            shifted == [false, false],
            "{line}"
        );
    }

    // The same seeds give the same angles; --resume keeps every sample and
    // runs none again.
    run(&[]);
    let again = read(".csv");
    assert_eq!(tradeoff_rows(&again), rows);
    run(&["--resume"]);
    assert_eq!(read(".csv"), again);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_free_run_in_3d_writes_spheres_with_their_height_to_vtk() {
    let dir = repose_testkit::scratch_dir("repose-cli-3d");
    let scene = dir.join("drop.toml");
    std::fs::write(
        &scene,
        "protocol = \"free_run\"\ndimension = 3\nduration = 0.02\n\
         [material]\nyoungs_modulus = 1e8\n\
         [[particles]]\nposition = [0.0, 0.0, 0.05]\nradius = 0.0005\n\
         [[particles]]\nposition = [0.01, 0.002, 0.003]\nvelocity = [0.5, 0.0, -1.0]\nradius = 0.0005\n\
         [[walls]]\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\n",
    )
    .unwrap();
    let vtk = dir.join("drop.vtk");
    let out = repose(&[
        "run",
        scene.to_str().unwrap(),
        "--vtk",
        vtk.to_str().unwrap(),
    ]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    // In 3D a free run takes Elekes & Parteli's rotating spheres, in SI units.
    assert!(
        stdout.contains("free_run (3D, model elekes_parteli"),
        "{stdout}"
    );
    let vtk = std::fs::read_to_string(vtk).unwrap();
    let points: Vec<Vec<f64>> = vtk
        .lines()
        .skip_while(|l| !l.starts_with("POINTS"))
        .skip(1)
        .take(2)
        .map(|l| l.split(' ').map(|x| x.parse().unwrap()).collect())
        .collect();
    // The first sphere fell freely for 0.02 s: z = 0.05 − g t²/2.
    assert_eq!(points[0].len(), 3);
    let expected = 0.05 - 0.5 * 9.81 * 0.02 * 0.02;
    assert!((points[0][2] - expected).abs() < 1e-6, "{points:?}");
    assert!(points[1][1] == 0.002, "{points:?}");
    // The second hit the plate sliding and left it spinning.
    assert!(vtk.contains("VECTORS angular_velocity double"));
    let spin: Vec<f64> = vtk
        .lines()
        .skip_while(|l| !l.starts_with("VECTORS angular_velocity"))
        .nth(2)
        .unwrap()
        .split(' ')
        .map(|x| x.parse().unwrap())
        .collect();
    assert!(spin[1] > 0.0, "{spin:?}");
    // A 2D vector where a 3D one is needed is refused, naming the field.
    let out = repose(&[
        "run",
        scene.to_str().unwrap(),
        "--set",
        "gravity=[0, -9.81]",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("gravity"),
        "{}",
        text(&out.stderr)
    );
    std::fs::remove_dir_all(dir).ok();
}

/// `repose serve` beyond loopback: refused without a token, started with one.
#[test]
fn serve_refuses_a_public_address_without_a_token() {
    let dir = repose_testkit::scratch_dir("repose-cli-serve");
    let db = format!("sqlite://{}", dir.join("serve.db").display());
    let serve = |env: &[(&str, &str)], extra: &[&str]| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_repose"));
        c.args([
            "serve",
            "--listen",
            "0.0.0.0:0",
            "--workers",
            "0",
            "--database",
            &db,
        ])
        .args(extra)
        .env_remove("REPOSE_TOKEN")
        .env_remove("REPOSE_TOKEN_FILE")
        .envs(env.iter().copied())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped());
        c
    };
    let out = serve(&[], &[]).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("without an access token"),
        "{}",
        text(&out.stderr)
    );
    let short = dir.join("short-token");
    std::fs::write(&short, "abc\n").unwrap();
    let out = serve(&[], &["--token-file", short.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("--token-file"),
        "{}",
        text(&out.stderr)
    );
    // With a token it serves (and says the token guards changes, not the token).
    let secret = "0123456789abcdef-secret";
    let mut child = serve(&[("REPOSE_TOKEN", secret)], &[]).spawn().unwrap();
    let mut line = String::new();
    std::io::BufRead::read_line(
        &mut std::io::BufReader::new(child.stdout.take().unwrap()),
        &mut line,
    )
    .unwrap();
    let _ = child.kill();
    let out = child.wait_with_output().unwrap();
    assert!(line.contains("token required to change"), "{line}");
    assert!(!line.contains(secret) && !text(&out.stderr).contains(secret));
}

#[test]
fn a_rewritten_report_takes_the_presets_bias_from_the_study_beside_it() {
    // The committed ep21 report (run at `paper`), beside a speed/accuracy
    // CSV whose `paper` heaps stand 10° ± 1.4° above glass's at a tenth of
    // its particle-steps (and twice its wall time, as if run on a slower
    // machine).
    let dir = repose_testkit::scratch_dir("repose-rewrite");
    let json = dir.join("reproduction-ep21.json");
    std::fs::copy(workspace().join("docs/reproduction-ep21.json"), &json).unwrap();
    let row = |setting: &str, seed: u32, theta: f64, wall: f64, steps: u64| {
        format!(
            "{setting},presets,{seed},completed,{theta},{theta},1000,1.0,6.3e10,{wall},{steps},\n"
        )
    };
    let csv = [
        "setting,group,seed,status,theta_r,theta_r_footprint,heap_grains,surface_roughness,youngs_modulus,wall_time_s,particle_steps,reason\n".to_string(),
        row("paper", 1, 50.0, 20.0, 1000),
        row("paper", 2, 52.0, 20.0, 1000),
        row("Y 63 GPa (glass)", 1, 40.0, 10.0, 10_000),
        row("Y 63 GPa (glass)", 2, 42.0, 10.0, 10_000),
    ]
    .concat();
    std::fs::write(dir.join("tradeoff-heap.csv"), csv).unwrap();
    let out = repose(&["reproduce", "--rewrite", json.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let md = std::fs::read_to_string(dir.join("reproduction-ep21.md")).unwrap();
    assert!(
        md.contains(
            "the `paper` preset stands +10.0° ± 1.4° from glass's 63 GPa at 0.10× its particle-steps"
        ),
        "{md}"
    );
    // The comparison is recomputed from the saved points, not dropped.
    assert!(md.contains("D_E (eq. 2 with α = ½)"), "{md}");
}

#[test]
fn measure_heap_reads_a_heap_from_its_grains_as_the_protocol_read_it() {
    // The reduced heap of softened grains (a few seconds), its final grains
    // written as the table another engine's dump becomes, then read back:
    // the same metrics to the bit.
    let out = repose(&[
        "run",
        "examples/heap.toml",
        "--set",
        "heap.plate=20",
        "--set",
        "heap.max_grains=1500",
        "--json",
        "--state",
        "-q",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["outcome"]["status"], "completed", "{report}");
    let grains = report["final_state"]["grains"].as_array().unwrap();
    let table: String = grains
        .iter()
        .map(|g| {
            let p: Vec<f64> = serde_json::from_value(g["position"].clone()).unwrap();
            format!("{} {} {} {}\n", p[0], p[1], p[2], g["radius"])
        })
        .collect();
    let file = repose_testkit::scratch_dir("measure-heap").join("grains.txt");
    std::fs::write(&file, table).unwrap();
    let path = file.to_str().unwrap();
    let measured = repose(&[
        "measure-heap",
        path,
        "--diameter",
        "1e-3",
        "--plate",
        "20",
        "--json",
    ]);
    assert!(measured.status.success(), "{}", text(&measured.stderr));
    let metrics: serde_json::Map<String, serde_json::Value> =
        serde_json::from_slice(&measured.stdout).unwrap();
    assert_eq!(metrics.len(), 8);
    for (name, value) in &metrics {
        assert_eq!(value, &report["metrics"][name], "{name}");
    }
    assert!(metrics["theta_r"].as_f64().unwrap() > 5.0);
    // Bad input: a plate that is no positive number, and a file of no grains.
    let empty = file.with_file_name("empty.txt");
    std::fs::write(&empty, "# nothing\n").unwrap();
    for (grains, plate, said) in [
        (path, "-1", "--plate"),
        (empty.to_str().unwrap(), "20", "no grains"),
    ] {
        let out = repose(&[
            "measure-heap",
            grains,
            "--diameter",
            "1e-3",
            "--plate",
            plate,
        ]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(said), "{stderr}");
    }
}
