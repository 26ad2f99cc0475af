//! The results browser in a real headless Chromium against `repose serve`
//! with small finished sweeps: the list shows them, every figure of the
//! paper draws from the API's study data, a sweep draws as a paper's figure,
//! a sample page draws its pile and its recorded curves, the buttons behind
//! the paper's figures queue the study's sweeps, and a bad form entry shows
//! the API's message beside the field. Screenshots go to
//! `target/screenshots/`.
//!
//! Chromium is `/usr/bin/chromium` (Debian's package; `.ci/run` installs it)
//! or `REPOSE_CHROMIUM`. With `CI=true` a missing browser fails the test;
//! elsewhere the test says so and skips.

use base64::Engine;
use serde_json::{json, Value};
use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

#[path = "common/mod.rs"]
mod common;

use common::{get, run_sweep, scratch, Server};

fn start_server() -> Server {
    Server::start(&format!("sqlite://{}", scratch("page.db").display()), 2)
}

fn chromium() -> Option<PathBuf> {
    let path = PathBuf::from(
        std::env::var("REPOSE_CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into()),
    );
    let how = format!("looked for {}; .ci/run installs it", path.display());
    repose_testkit::needs(path.exists(), "Chromium", &how).then_some(path)
}

fn screenshots() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/screenshots");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Headless Chromium driven over the DevTools protocol: one page, with
/// navigate, evaluate and screenshot. Written here so the test needs no
/// driver binary and nothing fetched at build time.
struct Page {
    /// The server the page's fragments are opened on, and visits so far.
    base: String,
    visits: u32,
    chrome: Child,
    socket: WebSocket<MaybeTlsStream<TcpStream>>,
    session: String,
    next_id: u64,
    profile: PathBuf,
}

impl Page {
    fn launch(binary: &PathBuf) -> Page {
        let profile = repose_testkit::scratch_dir("repose-chromium");
        let mut chrome = Command::new(binary)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                // WebGL on the CPU (the heap viewer)
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--hide-scrollbars",
                "--window-size=1280,900",
                "--remote-debugging-port=0",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg("about:blank")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("Chromium starts");
        let mut lines = BufReader::new(chrome.stderr.take().unwrap()).lines();
        let ws = loop {
            let line = lines
                .next()
                .expect("Chromium printed its DevTools address")
                .unwrap();
            if let Some(at) = line.find("ws://") {
                break line[at..].trim().to_string();
            }
        };
        // keep draining Chromium's log so it never blocks on a full pipe
        std::thread::spawn(move || for _ in lines {});
        let (socket, _) = tungstenite::connect(ws.as_str()).expect("DevTools socket");
        let mut page = Page {
            base: String::new(),
            visits: 0,
            chrome,
            socket,
            session: String::new(),
            next_id: 0,
            profile,
        };
        let target = page.call(None, "Target.createTarget", json!({"url": "about:blank"}));
        let attached = page.call(
            None,
            "Target.attachToTarget",
            json!({"targetId": target["targetId"], "flatten": true}),
        );
        page.session = attached["sessionId"].as_str().unwrap().to_string();
        page.command("Page.enable", json!({}));
        page.command(
            "Emulation.setDeviceMetricsOverride",
            json!({"width": 1280, "height": 900, "deviceScaleFactor": 1, "mobile": false}),
        );
        page
    }

    fn call(&mut self, session: Option<&str>, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut msg = json!({"id": id, "method": method, "params": params});
        if let Some(s) = session {
            msg["sessionId"] = json!(s);
        }
        self.socket.send(Message::text(msg.to_string())).unwrap();
        loop {
            let Message::Text(text) = self.socket.read().unwrap() else {
                continue;
            };
            let v: Value = serde_json::from_str(&text).unwrap();
            if v["id"] == id {
                assert!(v.get("error").is_none(), "{method}: {v}");
                return v["result"].clone();
            }
        }
    }

    fn command(&mut self, method: &str, params: Value) -> Value {
        let session = self.session.clone();
        self.call(Some(&session), method, params)
    }

    fn evaluate(&mut self, expression: &str) -> Value {
        let r = self.command(
            "Runtime.evaluate",
            json!({"expression": expression, "returnByValue": true, "awaitPromise": true}),
        );
        r["result"]["value"].clone()
    }

    /// Opens a view of the page (`#/sweep/ID`) as a fresh load.
    fn visit(&mut self, fragment: &str) {
        self.visits += 1;
        let url = format!("{}/?v={}#{fragment}", self.base, self.visits);
        self.open(&url);
    }

    fn open(&mut self, url: &str) {
        self.command("Page.navigate", json!({"url": url}));
        let start = Instant::now();
        while self.evaluate("document.readyState === 'complete' && location.href") != json!(url) {
            assert!(
                start.elapsed() < Duration::from_secs(30),
                "{url} did not load"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    fn screenshot(&mut self, name: &str) {
        let r = self.command(
            "Page.captureScreenshot",
            json!({"format": "png", "captureBeyondViewport": true}),
        );
        let png = base64::engine::general_purpose::STANDARD
            .decode(r["data"].as_str().unwrap())
            .unwrap();
        std::fs::write(screenshots().join(name), png).unwrap();
    }
}

impl Drop for Page {
    fn drop(&mut self) {
        let _ = self.chrome.kill();
        let _ = self.chrome.wait();
        let _ = std::fs::remove_dir_all(&self.profile);
    }
}

/// Evaluates a JS expression until it returns a truthy value.
fn wait_for(tab: &mut Page, what: &str, expression: &str) -> Value {
    let start = Instant::now();
    loop {
        let v = tab.evaluate(expression);
        let truthy = match &v {
            Value::Null | Value::Bool(false) => false,
            Value::Number(n) => n.as_f64() != Some(0.0),
            Value::String(s) => !s.is_empty(),
            _ => true,
        };
        if truthy {
            return v;
        }
        if start.elapsed() > Duration::from_secs(30) {
            tab.screenshot("failure.png");
            let text = tab.evaluate("document.body.innerText");
            panic!("the page never showed {what}; it shows:\n{text}");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

fn count(tab: &mut Page, selector: &str) -> u64 {
    tab.evaluate(&format!("document.querySelectorAll({selector:?}).length"))
        .as_u64()
        .unwrap_or(0)
}

#[test]
fn the_results_browser_shows_sweeps_figures_and_piles() {
    let Some(chrome) = chromium() else { return };
    let server = start_server();
    let rt = tokio::runtime::Runtime::new().unwrap();

    // A small sweep, run to the end by the server's workers.
    let spec = json!({
        "name": "browser check: θ_R against μ",
        "protocol": "fill_release",
        "base": {"box": {"width": 2.0, "height": 2.0}},
        "axes": {"contact.mu": [0.1, 0.3]},
        "samples": 2,
        "target_sem": 100.0,
        "max_samples": 4,
        "fidelity": "quick"
    });
    let flux = json!({
        "name": "browser check: constant flux",
        "protocol": "flux",
        "base": {"box": {"width": 2.0}, "flux": {"insertions": 30}},
        "samples": 1,
        "fidelity": "quick"
    });
    // A forced step of 0.3 t_c: accepted, but every fill fails a guard.
    let coarse = json!({
        "protocol": "fill_release",
        "base": {"box": {"width": 1.6, "height": 1.6}, "numerics": {"dt": 2.1e-4}},
        "samples": 1,
        "fidelity": "quick"
    });
    let (id, hash, grains, flux_hash, coarse_id) = rt.block_on(async {
        let id = run_sweep(&server, &spec).await;
        let flux_id = run_sweep(&server, &flux).await;
        let coarse_id = run_sweep(&server, &coarse).await;
        run_study(&server, "lh93").await;
        run_study(&server, "ep21").await;
        let first_sample = |sweep: String| {
            let url = server.url.clone();
            async move {
                let samples = get(&format!("{url}/api/sweeps/{sweep}/samples")).await;
                samples["samples"][0]["sample_hash"]
                    .as_str()
                    .unwrap()
                    .to_string()
            }
        };
        let hash = first_sample(id.clone()).await;
        let report = get(&format!("{}/api/samples/{hash}", server.url)).await;
        let grains = report["final_state"]["grains"].as_array().unwrap().len() as u64;
        let flux_hash = first_sample(flux_id).await;
        (id, hash, grains, flux_hash, coarse_id)
    });

    let mut tab = Page::launch(&chrome);
    tab.base = server.url.clone();

    the_list_and_the_sweep(&mut tab, &id);
    the_sweep_as_figures(&mut tab, &id);
    the_samples(&mut tab, &hash, grains, &flux_hash);
    the_form_and_the_reports(&mut tab);
    a_failed_sample(&mut tab, &coarse_id);
    the_study_buttons(&mut tab, &server, &rt);
    the_second_paper(&mut tab, &server, &rt);
}

fn the_list_and_the_sweep(tab: &mut Page, id: &str) {
    // 1. The list shows the sweep, done.
    tab.visit("/");
    wait_for(
        tab,
        "the sweep in the list",
        "document.querySelector('#sweeps tbody tr[data-id]')",
    );
    let row = wait_for(
        tab,
        "the finished sweep",
        &format!("(() => {{ const r = document.querySelector('tr[data-id=\"{id}\"]'); return r && r.innerText.includes('4 done') && r.innerText; }})()"),
    );
    assert!(row.as_str().unwrap().contains("browser check"), "{row}");
    tab.screenshot("sweeps.png");

    // 2. The sweep's own page: a plot over its axis, its points and samples.
    tab.visit(&format!("/sweep/{id}"));
    wait_for(
        tab,
        "the sweep's plot",
        "document.querySelectorAll('#generic-plot svg circle.mean').length === 2",
    );
    assert_eq!(count(tab, "#points tbody tr"), 2);
    assert_eq!(count(tab, "#samples tbody tr"), 4);
    // Each point's standard error against the sweep's target.
    let targets = tab.evaluate(
        "[...document.querySelectorAll('#points td.target')].map(td => td.innerText).join('|')",
    );
    let targets = targets.as_str().unwrap_or_default();
    assert_eq!(targets.matches("/ 100").count(), 2, "{targets}");
    assert_eq!(targets.matches("reached").count(), 2, "{targets}");
    tab.screenshot("sweep.png");
}

fn the_sweep_as_figures(tab: &mut Page, id: &str) {
    // 3. The sweep drawn as the paper's figure 3: both points with error
    //    bars, every sample, and atan(3μ) from the API.
    assert!(count(tab, &format!("a[href='#/sweep/{id}/figure/lh93/3']")) == 1);
    tab.visit(&format!("/sweep/{id}/figure/lh93/3"));
    wait_for(
        tab,
        "the figure",
        "document.querySelectorAll('#figure-plot svg circle.mean').length === 2",
    );
    assert_eq!(count(tab, "#figure-plot svg g.errorbar"), 3);
    assert_eq!(count(tab, "#figure-plot svg circle.sample"), 4);
    assert_eq!(count(tab, "#figure-plot svg polyline.theory"), 1);
    assert_eq!(count(tab, "#figure-plot svg circle.quoted"), 1);
    let title = wait_for(
        tab,
        "a hover text",
        "document.querySelector('#figure-plot circle.mean title').textContent",
    );
    assert!(title.as_str().unwrap().contains("n = 2"), "{title}");
    tab.screenshot("sweep-as-figure3.png");

    // Every figure of the paper, drawn from the study data the API serves.
    paper_figures(tab);
}

fn the_samples(tab: &mut Page, hash: &str, grains: u64, flux_hash: &str) {
    // 4. A sample page draws every grain, force chains, the surface and the energy trace.
    tab.visit(&format!("/sample/{hash}"));
    wait_for(
        tab,
        "the pile",
        "document.querySelectorAll('#pile svg circle.grain').length",
    );
    assert_eq!(count(tab, "#pile svg circle.grain"), grains);
    assert!(count(tab, "#pile svg line.chain") > 0);
    assert_eq!(count(tab, "#pile svg polyline.surface"), 1);
    assert_eq!(count(tab, "#energy svg polyline.trace"), 1);
    let scene = wait_for(
        tab,
        "the scene",
        "document.querySelector('#scene-json').textContent",
    );
    assert!(scene
        .as_str()
        .unwrap()
        .contains("\"protocol\": \"fill_release\""));
    tab.screenshot("sample.png");

    // 5. The constant-flux sample: the angle series with its fluctuation band (fig. 5).
    tab.visit(&format!("/sample/{flux_hash}"));
    wait_for(
        tab,
        "the flux series",
        "document.querySelector('#series-pile_angle svg polyline.trace')",
    );
    assert_eq!(count(tab, "#series-pile_angle svg rect.band"), 1);
    tab.screenshot("flux.png");
}

fn the_form_and_the_reports(tab: &mut Page) {
    // 6. A bad value in the form: the API's message appears beside the axis.
    tab.visit("/new");
    wait_for(tab, "the form", "document.querySelector('#sweep-form')");
    tab.evaluate("document.querySelector('#f-axes input.values').value = '0.2, -0.5'");
    tab.evaluate("document.querySelector('#f-submit').click()");
    let msg = wait_for(
        tab,
        "the validation message",
        "document.querySelector('#f-axes .field-error').textContent",
    );
    let msg = msg.as_str().unwrap();
    assert!(
        msg.contains("axes.contact.mu") && msg.contains("0 or more"),
        "{msg}"
    );
    tab.screenshot("form-error.png");

    // 7. Help shows the speed/accuracy report: its tables and both plots.
    tab.visit("/help");
    wait_for(
        tab,
        "the speed/accuracy report",
        "document.querySelector('#speed-accuracy .doc table')",
    );
    assert!(count(tab, "#speed-accuracy .doc table") >= 3);
    // Its list of reports links every paper's, as the studies name them.
    let linked = tab.evaluate(
        "Array.from(document.querySelectorAll('ul.reports a')).map(a => a.getAttribute('href')).join(' ')",
    );
    for paper in repose_studies::papers::PAPERS {
        let href = format!("#/doc/{}", paper.report);
        let listed = linked.as_str().unwrap().split(' ').any(|h| h == href);
        assert!(listed, "{href} in {linked}");
    }
    assert_eq!(count(tab, "#speed-accuracy .doc img"), 2);
    let loaded = wait_for(
        tab,
        "the plots to load",
        "Array.from(document.querySelectorAll('#speed-accuracy img')).every(i => i.complete && i.naturalWidth > 0) || null",
    );
    assert_eq!(loaded, json!(true));
    tab.screenshot("help.png");

    // 8. The reproduction report, linked from Help, with every figure.
    tab.evaluate("document.querySelector('a[href=\"#/doc/reproduction\"]').click()");
    wait_for(
        tab,
        "the reproduction report",
        "document.querySelector('.doc h2') && document.querySelectorAll('.doc img').length >= 9 || null",
    );
    let title = tab.evaluate("document.querySelector('.doc h2').textContent");
    assert!(title.as_str().unwrap().contains("Reproduction"), "{title}");
    let loaded = wait_for(
        tab,
        "the figures to load",
        "Array.from(document.querySelectorAll('.doc img')).every(i => i.complete && i.naturalWidth > 0) || null",
    );
    assert_eq!(loaded, json!(true));
    tab.screenshot("reproduction.png");
}

fn a_failed_sample(tab: &mut Page, coarse_id: &str) {
    // 9. A failed sample says why, in the sweep's sample list and on its own page.
    tab.visit(&format!("/sweep/{coarse_id}"));
    let reason = wait_for(
        tab,
        "the failed sample's reason",
        "(() => { const r = document.querySelector('#samples tbody tr'); return r && r.querySelector('.tag.failed') && r.querySelector('.reason') && r.querySelector('.reason').textContent; })()",
    );
    let reason = reason.as_str().unwrap().to_string();
    assert!(reason.contains("time step"), "{reason}");
    // Every job ran (a failed sample is a stored result): the sweep has finished.
    let state = tab.evaluate("document.querySelector('.panel .tag').textContent");
    assert_eq!(state, json!("finished"));
    tab.screenshot("failed-sweep.png");
    tab.evaluate("document.querySelector('#samples tbody tr a').click()");
    let shown = wait_for(
        tab,
        "the failed sample's page",
        "document.querySelector('#pile') && document.querySelector('.panel .tag.failed') && document.querySelector('.panel p').textContent",
    );
    assert!(
        shown.as_str().unwrap().contains(&reason),
        "{reason} / {shown}"
    );
    tab.screenshot("failed-sample.png");
}

fn the_study_buttons(tab: &mut Page, server: &Server, rt: &tokio::runtime::Runtime) {
    // 10. The button behind figure 3 queues the study's sweep, the one
    //     `repose reproduce` queues.
    tab.visit("/new");
    wait_for(
        tab,
        "the study buttons",
        "document.querySelector('button[data-study=\"lh93/fig347\"]')",
    );
    tab.evaluate("document.querySelector('button[data-study=\"lh93/fig347\"]').click()");
    let queued = wait_for(
        tab,
        "the queued study sweep",
        "location.hash.startsWith('#/sweep/') && location.hash.slice(8)",
    );
    let queued = queued.as_str().unwrap().to_string();
    rt.block_on(async {
        let sweep = get(&format!("{}/api/sweeps/{queued}", server.url)).await;
        assert_eq!(sweep["study"], "lh93/fig347");
        assert_eq!(sweep["spec"]["samples"], 20);
        assert_eq!(sweep["spec"]["fidelity"], "standard");
        // The paper's sweep is long: stop it.
        reqwest::Client::new()
            .post(format!("{}/api/sweeps/{queued}/cancel", server.url))
            .send()
            .await
            .unwrap();
    });
}

/// Queues every sweep of a paper's study (small, quick) and waits for them.
async fn run_study(server: &Server, paper: &str) {
    let client = reqwest::Client::new();
    let study = get(&format!("{}/api/studies/{paper}", server.url)).await;
    let mut ids = Vec::new();
    for sweep in study["sweeps"].as_array().unwrap() {
        let key = sweep["key"].as_str().unwrap();
        let created: Value = client
            .post(format!("{}/api/studies/{paper}/sweeps/{key}", server.url))
            .json(&json!({"fidelity": "quick", "reduced": true, "samples": 2}))
            .send()
            .await
            .unwrap()
            .json()
            .await
            .unwrap();
        ids.push(created["id"].as_str().unwrap().to_string());
    }
    for id in ids {
        common::wait_until(
            &format!("{}/api/sweeps/{id}", server.url),
            "a study sweep",
            Duration::from_secs(300),
            common::finished,
        )
        .await;
    }
}

/// Opens every figure of the paper and checks what it draws: means where it
/// measures, theory curves and quoted values where the study has them.
fn paper_figures(tab: &mut Page) {
    tab.visit("/papers");
    wait_for(
        tab,
        "the papers",
        "document.querySelector('[data-paper=\"lh93\"] ul li a')",
    );
    let figures = tab.evaluate(
        "Array.from(document.querySelectorAll('[data-paper=\"lh93\"] ul li a')).map(a => a.getAttribute('href'))",
    );
    let figures: Vec<String> = serde_json::from_value(figures).unwrap();
    assert_eq!(figures.len(), 9, "{figures:?}");
    // (figure, means drawn, theory curves, quoted values)
    let expected = [
        ("2a", 2, 0, 0),
        ("2b", 4, 0, 0),
        ("3", 3, 1, 1),
        ("4", 3, 1, 0),
        ("5", 0, 0, 0),
        ("7a", 3, 1, 0),
        ("7b", 3, 1, 0),
        ("k_n", 2, 0, 3),
        ("gamma_n", 2, 0, 3),
    ];
    for (fig, means, theory, quoted) in expected {
        tab.visit(&format!("/paper/lh93/figure/{fig}"));
        wait_for(
            tab,
            &format!("figure {fig}"),
            "document.querySelector('#figure-plot svg') && document.querySelectorAll('#figure-plot svg .series').length",
        );
        assert_eq!(
            count(tab, "#figure-plot svg circle.mean"),
            means,
            "figure {fig}"
        );
        assert_eq!(
            count(tab, "#figure-plot svg polyline.theory"),
            theory,
            "figure {fig}"
        );
        assert_eq!(
            count(tab, "#figure-plot svg circle.quoted"),
            quoted,
            "figure {fig}"
        );
        if fig == "5" {
            assert_eq!(count(tab, "#figure-plot svg polyline.trace"), 1);
            assert_eq!(count(tab, "#figure-plot svg polyline.level"), 1);
            assert_eq!(count(tab, "#figure-plot svg rect.band"), 1);
        }
        tab.screenshot(&format!("paper-figure-{fig}.png"));
    }
}

/// The completed sample with the most grains of the newest sweep queued
/// for a study sweep (`ep21/heaps`), by its metric `grains`.
async fn study_sample(server: &Server, study: &str, grains: &str) -> Option<String> {
    let sweeps = get(&format!("{}/api/sweeps", server.url)).await;
    let id = sweeps["sweeps"]
        .as_array()?
        .iter()
        .find(|s| s["study"] == study)?["id"]
        .as_str()?
        .to_string();
    let samples = get(&format!("{}/api/sweeps/{id}/samples", server.url)).await;
    let size = |s: &Value| s["metrics"][grains].as_f64().unwrap_or(0.0);
    samples["samples"]
        .as_array()?
        .iter()
        .filter(|s| s["outcome"] == "completed")
        .max_by(|a, b| size(a).total_cmp(&size(b)))?["sample_hash"]
        .as_str()
        .map(String::from)
}

/// Elekes & Parteli: every figure with its means, fits and their table,
/// regime I marked; a heap in 3D that turns, its side views with their
/// triangles and its pour history; a packing's sub-columns and φ(z).
fn the_second_paper(tab: &mut Page, server: &Server, rt: &tokio::runtime::Runtime) {
    tab.visit("/papers");
    wait_for(
        tab,
        "the second paper",
        "document.querySelector('[data-paper=\"ep21\"] ul li a')",
    );
    assert_eq!(count(tab, "[data-paper=\"ep21\"] ul li a"), 7);
    // (figure, fits it makes at least): what the reduced study draws
    // depends on which small heaps settle, so each figure is checked
    // against the figure data the API serves it.
    let expected = [
        ("2", 1),
        ("3a", 1),
        ("3b", 0),
        ("3c", 2),
        ("4", 1),
        ("5", 1),
        ("regime", 0),
    ];
    for (fig, fits) in expected {
        ep21_figure(tab, fig, fits);
    }
    let (heap, packing) = rt.block_on(async {
        (
            study_sample(server, "ep21/heaps", "heap_grains").await,
            study_sample(server, "ep21/packing", "bed_height").await,
        )
    });
    ep21_heap(tab, &heap.expect("a completed heap in the reduced study"));

    let packing = packing.expect("a completed packing in the reduced study");
    tab.visit(&format!("/sample/{packing}"));
    wait_for(
        tab,
        "the sub-columns",
        "document.querySelectorAll('#quarters tr').length",
    );
    assert_eq!(count(tab, "#quarters tr"), 4);
    assert_eq!(count(tab, "#series-phi_z svg polyline.trace"), 1);
    tab.screenshot("ep21-packing.png");

    // The paper's reproduction report, linked from the papers page.
    tab.visit("/papers");
    let link = wait_for(
        tab,
        "the report link",
        "document.querySelector('[data-paper=\"ep21\"] a.report') && document.querySelector('[data-paper=\"ep21\"] a.report').getAttribute('href')",
    );
    assert_eq!(link, "#/doc/reproduction-ep21");
    tab.visit("/doc/reproduction-ep21");
    wait_for(
        tab,
        "the second paper's report",
        "document.querySelector('.doc') && document.querySelector('.doc').textContent.includes('Reproduction of Elekes')",
    );
    assert!(count(tab, ".doc img") >= 7, "the report's figures");
    tab.screenshot("ep21-report.png");
}

/// One figure of the second paper: its means, and as many fits (at least
/// `fits`), failed fits, fitted curves and flagged points as the API serves.
fn ep21_figure(tab: &mut Page, fig: &str, fits: u64) {
    tab.visit(&format!("/paper/ep21/figure/{fig}"));
    wait_for(
        tab,
        &format!("ep21 figure {fig}"),
        "document.querySelector('#figure-plot svg') && document.querySelectorAll('#figure-plot svg circle.mean').length",
    );
    let served = tab.evaluate(&format!(
        "(async () => {{ const f = await (await fetch('/api/studies/ep21/figures/{fig}')).json(); \
         return [f.fits.length, f.fits.filter(x => x.fit).length, \
         f.series.filter(s => s.kind === 'measured').flatMap(s => s.points).filter(p => p.flag && Number.isFinite(p.y)).length]; }})()"
    ));
    let n = |k: usize| served[k].as_u64().unwrap();
    assert!(n(0) >= fits, "figure {fig}: {served}");
    assert_eq!(count(tab, "#fits tbody tr"), n(0), "figure {fig}");
    assert_eq!(
        count(tab, "#fits tbody tr.failed"),
        n(0) - n(1),
        "figure {fig}"
    );
    assert_eq!(
        count(tab, "#figure-plot svg polyline.fit"),
        n(1),
        "figure {fig}"
    );
    assert_eq!(
        count(tab, "#figure-plot svg circle.flagged"),
        n(2),
        "figure {fig}"
    );
    tab.screenshot(&format!("ep21-figure-{fig}.png"));
}

/// A heap of the second paper in 3D, turned by the arrow keys and drawn in
/// colour, with its side views, their triangles and its pour history.
fn ep21_heap(tab: &mut Page, heap: &str) {
    tab.visit(&format!("/sample/{heap}"));
    let drawn = wait_for(
        tab,
        "the heap in 3D",
        "document.querySelector('#grains3d') && document.querySelector('#grains3d').dataset.drawn",
    );
    assert!(drawn.as_str().unwrap().parse::<u64>().unwrap() > 10);
    let yaw = tab.evaluate("document.querySelector('#grains3d').dataset.yaw");
    tab.evaluate(
        "document.querySelector('#grains3d').dispatchEvent(new KeyboardEvent('keydown', {key: 'ArrowRight'}))",
    );
    assert_ne!(
        tab.evaluate("document.querySelector('#grains3d').dataset.yaw"),
        yaw,
        "the arrow key turns the heap"
    );
    // The canvas holds the heap's colours, not only the white background.
    let coloured = tab.evaluate(
        "(() => { const c = document.querySelector('#grains3d'); const gl = c.getContext('webgl'); \
         const px = new Uint8Array(c.width * c.height * 4); gl.readPixels(0, 0, c.width, c.height, gl.RGBA, gl.UNSIGNED_BYTE, px); \
         let n = 0; for (let i = 0; i < px.length; i += 4) if (px[i] < 200 || px[i + 2] < 200) n++; return n; })()",
    );
    assert!(coloured.as_u64().unwrap() > 1000, "{coloured}");
    for view in ["xz", "yz"] {
        assert_eq!(count(tab, &format!("#side-{view} svg polygon.triangle")), 1);
        assert_eq!(count(tab, &format!("#side-{view} svg polygon.outline")), 1);
    }
    let title = tab.evaluate("document.querySelector('#side-xz svg text').textContent");
    assert!(title.as_str().unwrap().contains("θ_r ="), "{title}");
    assert_eq!(count(tab, "#energy svg polyline.trace"), 1);
    assert_eq!(count(tab, "#series-heap_grains svg polyline.trace"), 1);
    tab.screenshot("ep21-heap.png");
}
