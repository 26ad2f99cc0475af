//! Generated requests against every route of the router over a real SQLite
//! store holding a finished sweep: random methods, paths with real and
//! garbled ids, query strings, malformed, deeply nested and wrongly typed
//! JSON, huge numbers, NaN and Infinity spelled as strings, unknown keys.
//! Every answer must be a 2xx, 3xx or 4xx; a 5xx or a panic fails the test.
//! The generator is ChaCha8 from a fixed seed, so a failure repeats.

mod common;

use axum::body::Body;
use axum::http::{Request, StatusCode};
use http_body_util::BodyExt;
use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use repose_store::Store;
use serde_json::{json, Map, Value};
use std::collections::BTreeMap;
use tower::ServiceExt;

/// Requests sent in all (the fuzz test's budget).
const REQUESTS: usize = 10_000;

const METHODS: [&str; 7] = ["GET", "POST", "PUT", "DELETE", "PATCH", "HEAD", "OPTIONS"];

/// Every route, with `{..}` where a path parameter goes.
const ROUTES: [&str; 22] = [
    "/",
    "/static/{file}",
    "/docs/{file}",
    "/api/health",
    "/api/openapi.json",
    "/api/protocols",
    "/api/studies",
    "/api/studies/{paper}",
    "/api/studies/{paper}/sweeps/{key}",
    "/api/studies/{paper}/figures/{figure}",
    "/api/studies/{paper}/comparison",
    "/api/sweeps",
    "/api/sweeps/{id}",
    "/api/sweeps/{id}/cancel",
    "/api/sweeps/{id}/retry",
    "/api/sweeps/{id}/samples",
    "/api/sweeps/{id}/points",
    "/api/sweeps/{id}/series",
    "/api/sweeps/{id}/figures",
    "/api/sweeps/{id}/figures/{paper}/{figure}",
    "/api/samples/{hash}",
    "/api/{file}",
];

const QUERY_KEYS: [&str; 9] = [
    "format", "x", "y", "series", "sweeps", "limit", "offset", "metric", "what",
];

/// Scalars that break naive code: huge, tiny, negative, non-finite
/// spellings, empty, very long, control and non-ASCII characters.
const NASTY: [&str; 18] = [
    "",
    "0",
    "-1",
    "1e309",
    "-1e309",
    "NaN",
    "Infinity",
    "-Infinity",
    "18446744073709551616",
    "9223372036854775807",
    "null",
    "true",
    "../../etc/passwd",
    "%00",
    "\u{0}",
    "ünïcødé",
    "csv",
    "a:b,c",
];

struct Gen {
    rng: ChaCha8Rng,
    /// Real values for path parameters, so that requests reach the handlers.
    real: BTreeMap<&'static str, Vec<String>>,
    spec: Value,
}

impl Gen {
    fn below(&mut self, n: usize) -> usize {
        (self.rng.next_u64() % n as u64) as usize
    }

    fn chance(&mut self, percent: u64) -> bool {
        self.rng.next_u64() % 100 < percent
    }

    fn pick<'a>(&mut self, from: &'a [&'a str]) -> &'a str {
        from[self.below(from.len())]
    }

    /// Random printable and unprintable characters.
    fn garbage(&mut self, max: usize) -> String {
        let len = self.below(max + 1);
        (0..len)
            .map(|_| match self.below(4) {
                0 => char::from(self.below(128) as u8),
                1 => char::from_u32(0x80 + self.below(0x2000) as u32).unwrap_or('x'),
                _ => char::from(b'a' + self.below(26) as u8),
            })
            .collect()
    }

    fn text(&mut self) -> String {
        match self.below(4) {
            0 => self.pick(&NASTY).to_string(),
            1 => self.garbage(12),
            2 => "x".repeat(self.below(5000)),
            _ => self.garbage(3),
        }
    }

    fn segment(&mut self, name: &str) -> String {
        let real = self.real.get(name).filter(|v| !v.is_empty()).cloned();
        match real {
            Some(values) if self.chance(60) => values[self.below(values.len())].clone(),
            _ => self.text(),
        }
    }

    /// A route's own method most of the time (so that requests reach the
    /// handlers), any method otherwise; sweeps are created often.
    fn request_line(&mut self) -> (&'static str, String) {
        let route = if self.chance(25) {
            "/api/sweeps"
        } else {
            ROUTES[self.below(ROUTES.len())]
        };
        let own = if route == "/api/sweeps" && self.chance(80)
            || route.ends_with("/cancel")
            || route.ends_with("/retry")
            || route.contains("/sweeps/{key}")
        {
            "POST"
        } else {
            "GET"
        };
        let method = if self.chance(80) {
            own
        } else {
            METHODS[self.below(METHODS.len())]
        };
        (method, self.path(route))
    }

    fn path(&mut self, route: &str) -> String {
        let mut out = String::new();
        for part in route.split('/').skip(1) {
            out.push('/');
            match part.strip_prefix('{').and_then(|p| p.strip_suffix('}')) {
                Some(name) => out.push_str(&common::encode(&self.segment(name))),
                None => out.push_str(part),
            }
        }
        if self.chance(5) {
            out.push_str(["/", "//", "/extra", "/.."][self.below(4)]);
        }
        if self.chance(40) {
            let pairs: Vec<String> = (0..1 + self.below(4))
                .map(|_| {
                    let k = if self.chance(80) {
                        self.pick(&QUERY_KEYS).to_string()
                    } else {
                        self.text()
                    };
                    format!(
                        "{}={}",
                        common::encode(&k),
                        common::encode(&self.value_text())
                    )
                })
                .collect();
            out.push('?');
            out.push_str(&pairs.join("&"));
        }
        out
    }

    /// A query value: a real key or metric name as often as not.
    fn value_text(&mut self) -> String {
        let names = ["contact.mu", "theta_r", "fig347:", "json", "samples"];
        if self.chance(50) {
            names[self.below(names.len())].to_string()
        } else {
            self.text()
        }
    }

    fn json(&mut self, depth: usize) -> Value {
        let top = if depth > 4 { 6 } else { 9 };
        match self.below(top) {
            0 => Value::Null,
            1 => json!(self.chance(50)),
            2 => json!(self.rng.next_u64() as i64),
            3 => json!(f64::from_bits(self.rng.next_u64()))
                .as_f64()
                .map_or(json!(0.5), |v| json!(v)),
            4 => json!(self.pick(&NASTY)),
            5 => json!(self.text()),
            6 => Value::Array((0..self.below(5)).map(|_| self.json(depth + 1)).collect()),
            _ => {
                let mut m = Map::new();
                for _ in 0..self.below(6) {
                    let k = self.key();
                    m.insert(k, self.json(depth + 1));
                }
                Value::Object(m)
            }
        }
    }

    fn key(&mut self) -> String {
        let keys = [
            "protocol",
            "base",
            "axes",
            "samples",
            "fidelity",
            "seed",
            "name",
            "reduced",
            "numerics",
            "contact",
            "box",
            "grains",
            "material",
            "heap",
            "packing",
            "mu",
            "integrator",
            "dt_factor",
            "preset",
            "target_sem",
        ];
        if self.chance(80) {
            keys[self.below(keys.len())].to_string()
        } else {
            self.text()
        }
    }

    /// A valid sweep spec with one part replaced by something random.
    fn mutated_spec(&mut self) -> Value {
        let mut spec = self.spec.clone();
        let mut pointer = String::new();
        while let Some(at) = spec.pointer(&pointer) {
            let step = match at {
                Value::Object(m) if !m.is_empty() && self.chance(70) => {
                    m.keys().nth(self.below(m.len())).cloned()
                }
                Value::Array(a) if !a.is_empty() && self.chance(70) => {
                    Some(self.below(a.len()).to_string())
                }
                _ => None,
            };
            match step {
                Some(k) => {
                    pointer = format!("{pointer}/{}", k.replace('~', "~0").replace('/', "~1"))
                }
                None => break,
            }
        }
        let replacement = self.json(3);
        if let Some(at) = spec.pointer_mut(&pointer) {
            *at = replacement;
        }
        spec
    }

    fn body(&mut self) -> Option<Vec<u8>> {
        let text = match self.below(9) {
            0 => return None,
            1 => {
                return Some(
                    (0..self.below(64))
                        .map(|_| self.rng.next_u64() as u8)
                        .collect(),
                )
            }
            2 => "[".repeat(1 + self.below(20_000)),
            3 => format!("{}1{}", "{\"a\":".repeat(300), "}".repeat(300)),
            4 => self.garbage(40),
            5 | 6 => self.mutated_spec().to_string(),
            7 => {
                let mut s = self.mutated_spec().to_string().into_bytes();
                s.truncate(self.below(s.len() + 1));
                return Some(s);
            }
            _ => self.json(0).to_string(),
        };
        Some(text.into_bytes())
    }
}

async fn send(
    store: &Store,
    method: &str,
    uri: &str,
    body: Option<Vec<u8>>,
    ct: &str,
) -> StatusCode {
    let mut req = Request::builder().method(method).uri(uri);
    if !ct.is_empty() {
        req = req.header("content-type", ct);
    }
    let req = req
        .body(body.map(Body::from).unwrap_or_else(Body::empty))
        .expect("percent-encoded paths are valid URIs");
    let resp = repose_api::app(store.clone())
        .oneshot(req)
        .await
        .expect("the router is infallible");
    let status = resp.status();
    // Read the whole body, so that a failure while streaming it counts.
    resp.into_body().collect().await.expect("the body streams");
    status
}

/// A store holding one finished two-sample sweep, and the real values of
/// every kind of path parameter.
async fn seeded() -> (Store, BTreeMap<&'static str, Vec<String>>, Value) {
    let spec = common::small_sweep();
    let (store, id) = common::store_with_finished_sweep("fuzz", &spec).await;
    let hashes = common::sample_hashes(&store, &id).await;
    let study = common::get_json(&store, "/api/studies/lh93").await;
    let keys = |field: &str| -> Vec<String> {
        study[field]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|x| x["key"].as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default()
    };
    let mut real = BTreeMap::new();
    real.insert("id", vec![id]);
    real.insert("hash", hashes);
    real.insert("paper", vec!["lh93".to_string()]);
    real.insert("key", keys("sweeps"));
    real.insert("figure", keys("figures"));
    real.insert(
        "file",
        vec![
            "app.js".into(),
            "reproduction.md".into(),
            "style.css".into(),
        ],
    );
    (store, real, spec)
}

#[tokio::test]
async fn ten_thousand_generated_requests_get_no_5xx_and_no_panic() {
    let (store, real, spec) = seeded().await;
    assert!(!real["key"].is_empty() && !real["figure"].is_empty() && real["hash"].len() == 2);
    let mut gen = Gen {
        rng: ChaCha8Rng::seed_from_u64(0x5eed_f022),
        real,
        spec,
    };
    let mut by_status: BTreeMap<u16, usize> = BTreeMap::new();
    for n in 0..REQUESTS {
        let (method, uri) = gen.request_line();
        let body = gen.body();
        let ct = [
            "application/json",
            "text/plain",
            "",
            "application/json; charset=utf-8",
        ][gen.below(4)];
        let shown = body
            .as_ref()
            .map(|b| String::from_utf8_lossy(&b[..b.len().min(300)]).into_owned());
        let status = send(&store, method, &uri, body, ct).await;
        assert!(
            !status.is_server_error(),
            "request {n}: {method} {uri} ({ct}) {shown:?} answered {status}"
        );
        *by_status.entry(status.as_u16()).or_default() += 1;
    }
    println!("{REQUESTS} generated requests by status: {by_status:?}");
    // The generator reaches the handlers, not only the router's 404s.
    for code in [200, 400, 404, 405, 422] {
        assert!(
            by_status.get(&code).copied().unwrap_or(0) > 50,
            "{by_status:?}"
        );
    }
}
