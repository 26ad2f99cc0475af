//! The OpenAPI document as a contract, checked by requests generated from
//! it. The test reads the document from the router, and for every
//! operation builds requests from the schemas it declares:
//!
//! * valid ones: required parameters and fields filled with the declared
//!   examples where there are some (values that pass the checks only the
//!   physics knows), else enum members or values of the declared types,
//!   optional ones present about half the time, path ids taken from the
//!   store (one finished sweep) — each must be answered 2xx;
//! * the same with an id the store does not hold — answered 404;
//! * invalid ones, breaking one declared constraint (a missing required
//!   parameter or field, a value outside an enum, under a minimum, an empty
//!   string where one is refused, a wrong type, an unknown key, a body that
//!   is not JSON) — answered 4xx.
//!
//! Every answer must have a status the operation declares, a declared
//! content type, and a JSON body that validates against the declared
//! schema. No answer may be a 5xx. The generator is ChaCha8 from a fixed
//! seed, so a failure repeats.

mod common;

use axum::body::Body;
use axum::http::{header, Request, StatusCode};
use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use repose_store::Store;
use serde_json::{json, Map, Value};
use std::collections::{BTreeMap, HashMap};
use tower::ServiceExt;

/// Passes over every operation; each sends a valid request, an invalid
/// one and, where the path names a stored id, one with an unknown id.
const ROUNDS: usize = 100;

const SEED: u64 = 0xc0_47_2a_c7;

/// A value no enum of the document lists.
const UNLISTED: &str = "not-a-listed-value";

/// One operation of the document.
struct Op {
    method: String,
    path: String,
    spec: Value,
}

impl Op {
    fn params(&self, location: &str) -> Vec<&Value> {
        self.spec["parameters"]
            .as_array()
            .map(|ps| ps.iter().filter(|p| p["in"] == location).collect())
            .unwrap_or_default()
    }

    fn name(&self) -> String {
        format!("{} {}", self.method.to_uppercase(), self.path)
    }
}

/// What a request is meant to test.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Valid,
    UnknownId,
    Invalid,
}

/// A request before it is sent: path values, query pairs and body.
#[derive(Debug, Clone)]
struct Draft {
    path: BTreeMap<String, String>,
    query: Vec<(String, String)>,
    body: Option<Vec<u8>>,
    /// What was broken, for invalid requests.
    broken: String,
}

/// What exists, for path parameters: the store's ids, and the keys the
/// registries hold together (a paper's sweeps and figures, the figures a
/// sweep can be drawn as).
struct Real {
    sweep: String,
    hashes: Vec<String>,
    /// A job of the sweep whose sample has a checkpoint.
    job: String,
    /// Sweeps this test queued and has not cancelled yet: the ones it may
    /// cancel (a cancelled sweep can no longer be retried, so the finished
    /// one is never cancelled).
    queued: Vec<String>,
    study_sweeps: Vec<(String, String)>,
    study_figures: Vec<(String, String)>,
    sweep_figures: Vec<(String, String)>,
}

/// The generator: ChaCha8 and the document's schemas.
struct Gen {
    rng: ChaCha8Rng,
    doc: Value,
    schemas: Schemas,
}

impl Gen {
    fn below(&mut self, n: usize) -> usize {
        (self.rng.next_u64() % n.max(1) as u64) as usize
    }

    fn chance(&mut self, percent: u64) -> bool {
        self.rng.next_u64() % 100 < percent
    }

    fn pick<T: Clone>(&mut self, from: &[T]) -> T {
        from[self.below(from.len())].clone()
    }

    fn letters(&mut self, len: usize) -> String {
        (0..len)
            .map(|_| char::from(b'a' + self.below(26) as u8))
            .collect()
    }

    /// A schema with its `$ref` followed.
    fn resolve(&self, schema: &Value) -> Value {
        let mut s = schema.clone();
        while let Some(r) = s.get("$ref").and_then(Value::as_str) {
            let target = r.trim_start_matches('#');
            let mut next = self
                .doc
                .pointer(target)
                .unwrap_or_else(|| panic!("dangling reference {r}"))
                .clone();
            if let (Some(next), Some(own)) = (next.as_object_mut(), s.as_object()) {
                for (k, v) in own {
                    if k != "$ref" {
                        next.insert(k.clone(), v.clone());
                    }
                }
            }
            s = next;
        }
        s
    }

    /// A value the schema accepts: an example if it gives any, else a
    /// constant, an enum member, a branch, or a value of its type.
    fn valid(&mut self, schema: &Value) -> Value {
        let s = self.resolve(schema);
        if let Some(examples) = s["examples"].as_array().filter(|e| !e.is_empty()) {
            return self.pick(examples);
        }
        if let Some(c) = s.get("const") {
            return c.clone();
        }
        if let Some(values) = s["enum"].as_array() {
            return self.pick(values);
        }
        for key in ["oneOf", "anyOf"] {
            if let Some(branches) = s[key].as_array() {
                let branch = self.pick(branches);
                return self.valid(&branch);
            }
        }
        let types = types(&s);
        let non_null: Vec<&str> = types.iter().copied().filter(|t| *t != "null").collect();
        let t = if non_null.is_empty() || (types.contains(&"null") && self.chance(15)) {
            types.first().copied().unwrap_or("integer")
        } else {
            self.pick(&non_null)
        };
        match t {
            "null" => Value::Null,
            "boolean" => json!(self.chance(50)),
            "integer" => self.integer(&s),
            "number" => self.number(&s),
            "string" => json!(self.string(&s)),
            "array" => {
                let n = s["minItems"].as_u64().unwrap_or(0) as usize + self.below(3);
                let items = s.get("items").cloned().unwrap_or(json!({}));
                Value::Array((0..n).map(|_| self.valid(&items)).collect())
            }
            _ => self.object(&s),
        }
    }

    fn integer(&mut self, s: &Value) -> Value {
        let lo = s["minimum"]
            .as_i64()
            .or_else(|| s["exclusiveMinimum"].as_i64().map(|m| m + 1))
            .unwrap_or(0);
        let hi = s["maximum"].as_i64().unwrap_or(i64::MAX).min(lo + 20);
        json!(lo + self.below((hi - lo + 1) as usize) as i64)
    }

    fn number(&mut self, s: &Value) -> Value {
        let lo = s["minimum"]
            .as_f64()
            .or_else(|| s["exclusiveMinimum"].as_f64().map(|m| m + 0.001))
            .unwrap_or(0.0);
        json!(lo + self.below(1000) as f64 / 100.0)
    }

    fn string(&mut self, s: &Value) -> String {
        assert!(
            s.get("pattern").is_none(),
            "a string with a pattern needs examples in the document: {s}"
        );
        let least = s["minLength"].as_u64().unwrap_or(0) as usize;
        let len = least.max(1 + self.below(8));
        self.letters(len)
    }

    fn object(&mut self, s: &Value) -> Value {
        let required = strings(&s["required"]);
        let mut out = Map::new();
        if let Some(props) = s["properties"].as_object() {
            for (name, p) in props {
                // A read-only property is the server's to set, never a request's.
                if self.resolve(p)["readOnly"] == json!(true) {
                    continue;
                }
                if required.contains(&name.as_str()) || self.chance(50) {
                    out.insert(name.clone(), self.valid(p));
                }
            }
        } else if let Some(extra) = s.get("additionalProperties").filter(|a| a.is_object()) {
            for _ in 0..self.below(3) {
                let key = self.key(&s["propertyNames"]);
                out.insert(key, self.valid(extra));
            }
        }
        self.apply_rules(s, &mut out);
        Value::Object(out)
    }

    fn key(&mut self, names: &Value) -> String {
        let names = self.resolve(names);
        match names["enum"].as_array() {
            Some(values) => self.pick(values).as_str().unwrap_or("key").to_string(),
            None => self.letters(6),
        }
    }

    /// Applies the schema's `if`/`then` parts to a generated object: the
    /// fields a rule requires are added, those it narrows are generated
    /// again from the narrowed schema.
    fn apply_rules(&mut self, s: &Value, out: &mut Map<String, Value>) {
        let Some(rules) = s["allOf"].as_array() else {
            return;
        };
        for rule in rules {
            let (Some(cond), Some(then)) = (rule.get("if"), rule.get("then")) else {
                continue;
            };
            if !self.schemas.is_valid(cond, &Value::Object(out.clone())) {
                continue;
            }
            let mut names: Vec<String> = strings(&then["required"])
                .into_iter()
                .map(String::from)
                .collect();
            if let Some(props) = then["properties"].as_object() {
                names.extend(props.keys().filter(|k| out.contains_key(*k)).cloned());
            }
            for name in names {
                let narrowed = narrow(
                    &self.resolve(&s["properties"][&name]),
                    &then["properties"][&name],
                );
                out.insert(name, self.valid(&narrowed));
            }
        }
    }
}

/// The schema `base` with the keywords of `over` laid on it; a new type,
/// enum or constant drops the examples of the old.
fn narrow(base: &Value, over: &Value) -> Value {
    let mut out = base.clone();
    let (Some(target), Some(over)) = (out.as_object_mut(), over.as_object()) else {
        return base.clone();
    };
    if ["type", "enum", "const"]
        .iter()
        .any(|k| over.contains_key(*k))
    {
        target.remove("examples");
        target.remove("enum");
    }
    target.extend(over.clone());
    out
}

fn types(s: &Value) -> Vec<&str> {
    match &s["type"] {
        Value::String(t) => vec![t.as_str()],
        Value::Array(ts) => ts.iter().filter_map(Value::as_str).collect(),
        _ if s.get("properties").is_some() => vec!["object"],
        _ => vec![],
    }
}

fn strings(v: &Value) -> Vec<&str> {
    v.as_array()
        .map(|a| a.iter().filter_map(Value::as_str).collect())
        .unwrap_or_default()
}

/// A parameter value as it goes in a URL.
fn text(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The document's schemas, compiled once each (by boon, a JSON Schema
/// 2020-12 validator).
struct Schemas {
    components: Value,
    compiler: boon::Compiler,
    compiled: boon::Schemas,
    index: HashMap<String, boon::SchemaIndex>,
}

impl Schemas {
    fn new(components: Value) -> Schemas {
        let mut compiler = boon::Compiler::new();
        compiler.set_default_draft(boon::Draft::V2020_12);
        Schemas {
            components,
            compiler,
            compiled: boon::Schemas::new(),
            index: HashMap::new(),
        }
    }

    /// The compiled `schema`, whose references point into the document's
    /// components.
    fn compile(&mut self, schema: &Value) -> boon::SchemaIndex {
        let key = schema.to_string();
        if let Some(index) = self.index.get(&key) {
            return *index;
        }
        let url = format!("http://contract.test/schema-{}.json", self.index.len());
        let root = json!({ "components": self.components, "allOf": [schema] });
        self.compiler
            .add_resource(&url, root)
            .expect("the address is well formed");
        let index = self
            .compiler
            .compile(&url, &mut self.compiled)
            .unwrap_or_else(|e| panic!("the document's schema {schema} does not compile: {e:#}"));
        self.index.insert(key, index);
        index
    }

    fn is_valid(&mut self, schema: &Value, instance: &Value) -> bool {
        let index = self.compile(schema);
        self.compiled.validate(instance, index).is_ok()
    }

    /// Why `instance` does not fit `schema`; empty if it does.
    fn errors(&mut self, schema: &Value, instance: &Value) -> String {
        let index = self.compile(schema);
        match self.compiled.validate(instance, index) {
            Ok(()) => String::new(),
            Err(e) => format!("{e}"),
        }
    }
}

/// One way of breaking a request.
#[derive(Debug, Clone)]
enum Break {
    /// Leave a required parameter out.
    Omit(String),
    /// Give a parameter a value its schema refuses.
    Param(String, String),
    /// Send no body where one is required.
    NoBody,
    /// Send a body that is not JSON.
    NotJson,
    /// Replace (or add) the value at a JSON pointer of the body.
    Set(String, Value),
    /// Remove the value at a JSON pointer of the body.
    Remove(String),
}

/// Values the schema refuses, each a candidate for an invalid request.
fn refused_values(s: &Value) -> Vec<Value> {
    let mut out = Vec::new();
    if s.get("enum").is_some() || s.get("const").is_some() {
        out.push(json!(UNLISTED));
    }
    let types = types(s);
    if !types.is_empty() {
        let wrong = [
            json!("text"),
            json!(12345),
            json!(true),
            json!([1]),
            json!({"a": 1}),
        ];
        let fits = |v: &Value| {
            types.iter().any(|t| match *t {
                "string" => v.is_string(),
                "integer" | "number" => v.is_number(),
                "boolean" => v.is_boolean(),
                "array" => v.is_array(),
                "object" => v.is_object(),
                _ => false,
            })
        };
        out.extend(wrong.into_iter().filter(|v| !fits(v)).take(1));
    }
    if let Some(m) = s["minimum"].as_i64() {
        out.push(json!(m - 1));
    }
    if let Some(m) = s["maximum"].as_i64() {
        out.push(json!(m as u64 + 1));
    } else if let Some(m) = s["maximum"].as_u64() {
        out.push(json!(m as f64 * 2.0));
    }
    if let Some(m) = s.get("exclusiveMinimum").filter(|m| m.is_number()) {
        out.push(m.clone());
    }
    if s["minLength"].as_u64().is_some_and(|n| n > 0) {
        out.push(json!(""));
    }
    if s.get("pattern").is_some() {
        out.extend(["", "a..b", "no-colon"].map(|v| json!(v)));
    }
    if s["minItems"].as_u64().is_some_and(|n| n > 0) {
        out.push(json!([]));
    }
    out
}

impl Gen {
    /// Every way of breaking `instance` by one declared constraint of
    /// `schema`, found by walking both together.
    fn body_breaks(&self, schema: &Value, instance: &Value, at: &str, out: &mut Vec<Break>) {
        let s = self.resolve(schema);
        for v in refused_values(&s) {
            out.push(Break::Set(at.to_string(), v));
        }
        match instance {
            Value::Object(m) => {
                for r in strings(&s["required"]) {
                    if m.contains_key(r) {
                        out.push(Break::Remove(format!("{at}/{r}")));
                    }
                }
                if s["additionalProperties"] == json!(false) {
                    out.push(Break::Set(format!("{at}/unexpected_field"), json!(1)));
                }
                for (k, p) in s["properties"].as_object().into_iter().flatten() {
                    if self.resolve(p)["readOnly"] == json!(true) {
                        out.push(Break::Set(format!("{at}/{k}"), json!("set-by-a-client")));
                    }
                }
                if s.get("propertyNames").is_some() {
                    for key in ["protocol", "seed", "preset", "a..b", UNLISTED] {
                        out.push(Break::Set(format!("{at}/{key}"), json!([1])));
                    }
                }
                for (k, v) in m {
                    let sub = s["properties"]
                        .get(k)
                        .or_else(|| s.get("additionalProperties").filter(|a| a.is_object()));
                    if let Some(sub) = sub {
                        let key = k.replace('~', "~0").replace('/', "~1");
                        self.body_breaks(sub, v, &format!("{at}/{key}"), out);
                    }
                }
            }
            Value::Array(items) => {
                for (i, v) in items.iter().enumerate() {
                    self.body_breaks(&s["items"], v, &format!("{at}/{i}"), out);
                }
            }
            _ => {}
        }
    }

    /// Ways of breaking a request's parameters and body.
    fn breaks(&self, op: &Op, body: Option<&Value>) -> Vec<Break> {
        let mut out = Vec::new();
        for p in op.params("query").into_iter().chain(op.params("path")) {
            let name = p["name"].as_str().unwrap_or_default().to_string();
            if p["required"] == true && p["in"] == "query" {
                out.push(Break::Omit(name.clone()));
            }
            for v in refused_values(&self.resolve(&p["schema"])) {
                if let Value::String(v) = v {
                    out.push(Break::Param(name.clone(), v));
                }
            }
        }
        if let Some(rb) = op.spec.get("requestBody") {
            out.push(Break::NotJson);
            if rb["required"] == true {
                out.push(Break::NoBody);
            }
            if let Some(body) = body {
                let schema = &rb["content"]["application/json"]["schema"];
                self.body_breaks(schema, body, "", &mut out);
            }
        }
        out
    }
}

/// `value` with the change at `pointer` made.
fn changed(value: &Value, brk: &Break) -> Option<Value> {
    let mut v = value.clone();
    let (pointer, new) = match brk {
        Break::Set(p, new) => (p.as_str(), Some(new.clone())),
        Break::Remove(p) => (p.as_str(), None),
        _ => return None,
    };
    if pointer.is_empty() {
        return new;
    }
    let (parent, last) = pointer.rsplit_once('/')?;
    let last = last.replace("~1", "/").replace("~0", "~");
    match (v.pointer_mut(parent)?, new) {
        (Value::Object(m), Some(new)) => {
            m.insert(last, new);
        }
        (Value::Object(m), None) => {
            m.remove(&last);
        }
        (Value::Array(a), Some(new)) => *a.get_mut(last.parse::<usize>().ok()?)? = new,
        _ => return None,
    }
    Some(v)
}

/// The generator, the store it sends to, and what it has seen.
struct Run {
    store: Store,
    gen: Gen,
    real: Real,
    /// Answers by operation and status.
    seen: BTreeMap<String, BTreeMap<u16, usize>>,
}

impl Run {
    /// Path values that name stored things, or None where there are none
    /// to name (nothing queued to cancel yet).
    fn path_values(&mut self, op: &Op) -> Option<BTreeMap<String, String>> {
        let names: Vec<String> = op
            .params("path")
            .iter()
            .filter_map(|p| p["name"].as_str().map(String::from))
            .collect();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let g = &mut self.gen;
        let pair = |a: &str, b: &str, (x, y): (String, String)| {
            BTreeMap::from([(a.to_string(), x), (b.to_string(), y)])
        };
        let values = match names.as_slice() {
            ["id"] if op.path.ends_with("/cancel") => {
                if self.real.queued.is_empty() {
                    return None;
                }
                // Each is cancelled once: a second cancel finds nothing to
                // cancel and answers 409.
                let k = g.below(self.real.queued.len());
                BTreeMap::from([("id".into(), self.real.queued.swap_remove(k))])
            }
            ["id"] if op.path.starts_with("/api/jobs/") => {
                BTreeMap::from([("id".into(), self.real.job.clone())])
            }
            ["id"] => BTreeMap::from([("id".into(), self.real.sweep.clone())]),
            ["hash"] => BTreeMap::from([("hash".into(), g.pick(&self.real.hashes))]),
            ["paper", "key"] => pair("paper", "key", g.pick(&self.real.study_sweeps)),
            ["paper", "figure"] => pair("paper", "figure", g.pick(&self.real.study_figures)),
            ["id", "paper", "figure"] => {
                let mut v = pair("paper", "figure", g.pick(&self.real.sweep_figures));
                v.insert("id".into(), self.real.sweep.clone());
                v
            }
            _ => op
                .params("path")
                .iter()
                .map(|p| (text(&p["name"]), text(&g.valid(&p["schema"]))))
                .collect(),
        };
        Some(values)
    }

    /// A request the document says is valid, or None if it cannot be made.
    fn valid_draft(&mut self, op: &Op) -> Option<(Draft, Option<Value>)> {
        let path = self.path_values(op)?;
        let mut query = Vec::new();
        for p in op.params("query") {
            if p["required"] != true && self.gen.chance(50) {
                continue;
            }
            let name = text(&p["name"]);
            let value = if name == "sweeps" {
                // A binding names a stored sweep.
                let (_, key) = self.gen.pick(&self.real.study_sweeps);
                format!("{key}:{}", self.real.sweep)
            } else {
                text(&self.gen.valid(&p["schema"]))
            };
            self.fits(&p["schema"], &json!(value), &name);
            query.push((name, value));
        }
        let mut body = None;
        if let Some(rb) = op.spec.get("requestBody") {
            if rb["required"] == true || self.gen.chance(70) {
                let schema = &rb["content"]["application/json"]["schema"];
                let value = self.gen.valid(schema);
                self.fits(schema, &value, "the body");
                body = Some(value);
            }
        }
        let draft = Draft {
            path,
            query,
            body: body.as_ref().map(|b| b.to_string().into_bytes()),
            broken: String::new(),
        };
        Some((draft, body))
    }

    /// A generated valid value does fit its schema (a check of the generator).
    fn fits(&mut self, schema: &Value, value: &Value, what: &str) {
        let errors = self.gen.schemas.errors(schema, value);
        assert!(errors.is_empty(), "generated {what} {value}: {errors}");
    }

    /// A valid request with one constraint broken, checked against the
    /// schemas so that it is invalid indeed.
    fn invalid_draft(&mut self, op: &Op) -> Option<Draft> {
        let (mut draft, body) = self.valid_draft(op)?;
        let mut breaks = self.gen.breaks(op, body.as_ref());
        while !breaks.is_empty() {
            let brk = breaks.swap_remove(self.gen.below(breaks.len()));
            if self.apply(op, &mut draft, body.as_ref(), &brk) {
                draft.broken = format!("{brk:?}");
                return Some(draft);
            }
        }
        None
    }

    /// Makes the break in `draft`; false if it would leave the request valid.
    fn apply(&mut self, op: &Op, draft: &mut Draft, body: Option<&Value>, brk: &Break) -> bool {
        let param_schema = |name: &str| {
            op.spec["parameters"]
                .as_array()
                .and_then(|ps| ps.iter().find(|p| p["name"] == name))
                .map(|p| p["schema"].clone())
                .unwrap_or(json!({}))
        };
        match brk {
            Break::Omit(name) => draft.query.retain(|(k, _)| k != name),
            Break::Param(name, value) => {
                let schema = param_schema(name);
                if self.gen.schemas.is_valid(&schema, &json!(value)) {
                    return false;
                }
                if let Some(v) = draft.path.get_mut(name) {
                    *v = value.clone();
                } else {
                    draft.query.retain(|(k, _)| k != name);
                    draft.query.push((name.clone(), value.clone()));
                }
            }
            Break::NoBody => draft.body = None,
            Break::NotJson => draft.body = Some(b"{\"protocol\": ".to_vec()),
            Break::Set(..) | Break::Remove(..) => {
                let schema = &op.spec["requestBody"]["content"]["application/json"]["schema"];
                let Some(new) = body.and_then(|b| changed(b, brk)) else {
                    return false;
                };
                if self.gen.schemas.is_valid(schema, &new) {
                    return false;
                }
                draft.body = Some(new.to_string().into_bytes());
            }
        }
        true
    }

    /// The same valid request with a stored id replaced by one the store
    /// does not hold.
    fn unknown_draft(&mut self, op: &Op) -> Option<Draft> {
        let (mut draft, _) = self.valid_draft(op)?;
        let key = ["id", "hash"]
            .into_iter()
            .find(|k| draft.path.contains_key(*k))?;
        draft
            .path
            .insert(key.into(), format!("no-such-{}", self.gen.letters(8)));
        Some(draft)
    }

    fn uri(op: &Op, draft: &Draft) -> String {
        let mut uri = op.path.clone();
        for (k, v) in &draft.path {
            uri = uri.replace(&format!("{{{k}}}"), &common::encode(v));
        }
        if !draft.query.is_empty() {
            let pairs: Vec<String> = draft
                .query
                .iter()
                .map(|(k, v)| format!("{}={}", common::encode(k), common::encode(v)))
                .collect();
            uri = format!("{uri}?{}", pairs.join("&"));
        }
        uri
    }
}

impl Run {
    /// Sends a request and checks the answer against the document; the status.
    async fn send(&mut self, op: &Op, draft: &Draft, kind: Kind) -> (StatusCode, Value) {
        let uri = Run::uri(op, draft);
        let mut req = Request::builder()
            .method(op.method.to_uppercase().as_str())
            .uri(&uri);
        if draft.body.is_some() {
            req = req.header(header::CONTENT_TYPE, "application/json");
        }
        let body = draft
            .body
            .clone()
            .map(Body::from)
            .unwrap_or_else(Body::empty);
        let resp = repose_api::app(self.store.clone())
            .oneshot(req.body(body).expect("encoded URIs are valid"))
            .await
            .expect("the router is infallible");
        let status = resp.status();
        let ctype = resp
            .headers()
            .get(header::CONTENT_TYPE)
            .and_then(|v| v.to_str().ok())
            .map(|v| v.split(';').next().unwrap_or_default().trim().to_string());
        let bytes = http_body_util::BodyExt::collect(resp.into_body())
            .await
            .expect("the body streams")
            .to_bytes();
        let shown = draft
            .body
            .as_ref()
            .map(|b| String::from_utf8_lossy(&b[..b.len().min(400)]).into_owned());
        let what = format!(
            "{kind:?} {} {uri} {shown:?} {} answered {status}: {}",
            op.method.to_uppercase(),
            draft.broken,
            String::from_utf8_lossy(&bytes[..bytes.len().min(400)])
        );
        let expected = match kind {
            Kind::Valid => status.is_success(),
            Kind::UnknownId => status == StatusCode::NOT_FOUND,
            Kind::Invalid => status.is_client_error(),
        };
        assert!(expected, "{what}");
        self.conforms(op, status, ctype.as_deref(), &bytes, &what);
        *self
            .seen
            .entry(op.name())
            .or_default()
            .entry(status.as_u16())
            .or_default() += 1;
        (
            status,
            serde_json::from_slice(&bytes).unwrap_or(Value::Null),
        )
    }

    /// The answer's status, content type and body are those the operation declares.
    fn conforms(
        &mut self,
        op: &Op,
        status: StatusCode,
        ctype: Option<&str>,
        bytes: &[u8],
        what: &str,
    ) {
        let responses = &op.spec["responses"];
        let declared = responses
            .get(status.as_str())
            .or_else(|| responses.get("default"))
            .unwrap_or_else(|| panic!("undeclared status: {what}"));
        let Some(content) = declared.get("content").and_then(Value::as_object) else {
            assert!(bytes.is_empty(), "a body where none is declared: {what}");
            return;
        };
        let ctype = ctype.unwrap_or_else(|| panic!("no content type: {what}"));
        let media = content
            .get(ctype)
            .unwrap_or_else(|| panic!("undeclared content type {ctype}: {what}"));
        if ctype != "application/json" {
            return;
        }
        let body: Value =
            serde_json::from_slice(bytes).unwrap_or_else(|e| panic!("not JSON ({e}): {what}"));
        let errors = self.gen.schemas.errors(&media["schema"], &body);
        assert!(errors.is_empty(), "{errors} in {what}");
    }

    /// One pass over every operation: a valid request, one with an
    /// unknown id, and an invalid one.
    async fn round(&mut self, ops: &[Op]) -> usize {
        let mut sent = 0;
        for op in ops {
            if let Some((draft, _)) = self.valid_draft(op) {
                let (status, answer) = self.send(op, &draft, Kind::Valid).await;
                sent += 1;
                if status == StatusCode::CREATED && op.path == "/api/sweeps" {
                    self.real.queued.push(text(&answer["id"]));
                }
            }
            if let Some(draft) = self.unknown_draft(op) {
                self.send(op, &draft, Kind::UnknownId).await;
                sent += 1;
            }
            if let Some(draft) = self.invalid_draft(op) {
                self.send(op, &draft, Kind::Invalid).await;
                sent += 1;
            }
        }
        sent
    }
}

/// Every operation of the document, in the document's order.
fn operations(doc: &Value) -> Vec<Op> {
    let mut ops = Vec::new();
    for (path, item) in doc["paths"].as_object().expect("the document has paths") {
        for (method, spec) in item.as_object().into_iter().flatten() {
            ops.push(Op {
                method: method.clone(),
                path: path.clone(),
                spec: spec.clone(),
            });
        }
    }
    ops
}

/// Every schema of the document compiles, and every example it gives
/// fits the schema it is given for (the generator takes examples as valid).
fn check_schemas(node: &Value, schemas: &mut Schemas) {
    match node {
        Value::Object(m) => {
            if let Some(examples) = m.get("examples").and_then(Value::as_array) {
                for example in examples {
                    let errors = schemas.errors(node, example);
                    assert!(errors.is_empty(), "example {example}: {errors}");
                }
            }
            if let Some(schema) = m.get("schema") {
                schemas.compile(schema);
            }
            for v in m.values() {
                check_schemas(v, schemas);
            }
        }
        Value::Array(items) => items.iter().for_each(|v| check_schemas(v, schemas)),
        _ => {}
    }
}

/// The store's ids and the registries' key pairs, read through the API.
async fn real_values(store: &Store, sweep: String) -> Real {
    let hashes = common::sample_hashes(store, &sweep).await;
    let studies = common::get_json(store, "/api/studies").await;
    let mut study_sweeps = Vec::new();
    let mut study_figures = Vec::new();
    for study in studies["studies"].as_array().into_iter().flatten() {
        let paper = text(&study["key"]);
        for s in study["sweeps"].as_array().into_iter().flatten() {
            study_sweeps.push((paper.clone(), text(&s["key"])));
        }
        for f in study["figures"].as_array().into_iter().flatten() {
            study_figures.push((paper.clone(), text(&f["key"])));
        }
    }
    let refs = common::get_json(store, &format!("/api/sweeps/{sweep}/figures")).await;
    let sweep_figures = refs["figures"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|f| (text(&f["paper"]), text(&f["figure"])))
        .collect();
    let job = job_with_checkpoint(store, &sweep).await;
    Real {
        sweep,
        hashes,
        job,
        queued: Vec::new(),
        study_sweeps,
        study_figures,
        sweep_figures,
    }
}

/// Keeps the first checkpoint a run saves, and stops the run there.
#[derive(Default)]
struct FirstSave(Option<repose_physics::Checkpoint>);

impl repose_physics::Observer for FirstSave {
    fn progress(&mut self, _: &repose_physics::Progress) -> bool {
        self.0.is_none()
    }
    fn checkpoint_due(&mut self) -> bool {
        self.0.is_none()
    }
    fn save(&mut self, checkpoint: repose_physics::Checkpoint) {
        self.0 = Some(checkpoint);
    }
}

/// A job of the finished `sweep` given a checkpoint, as a running long
/// sample has one: a saved run of three 2D grains (its scene is 2D too).
async fn job_with_checkpoint(store: &Store, sweep: &str) -> String {
    let scene = repose_physics::Scene::from_toml(
        "protocol = \"free_run\"\nduration = 0.1\n\
         [[particles]]\nposition = [0.0, 0.1]\nradius = 0.1\n\
         [[particles]]\nposition = [0.3, 0.1]\nradius = 0.1\n\
         [[particles]]\nposition = [0.6, 0.1]\nradius = 0.1\n",
        &[],
    )
    .unwrap();
    let mut first = FirstSave::default();
    repose_physics::run(&scene, &mut first).unwrap();
    let saved = first.0.expect("the run saves a checkpoint");
    let job: String = sqlx::query_scalar("SELECT id FROM jobs WHERE sweep_id = ? LIMIT 1")
        .bind(sweep)
        .fetch_one(store.pool())
        .await
        .unwrap();
    sqlx::query(
        "INSERT INTO checkpoints (job_id, owner, sim_time, iteration, state, saved_at) \
         VALUES (?, 'contract', ?, ?, ?, 0)",
    )
    .bind(&job)
    .bind(saved.time)
    .bind(saved.iteration as i64)
    .bind(saved.state)
    .execute(store.pool())
    .await
    .unwrap();
    job
}

#[tokio::test]
async fn every_operation_keeps_the_documented_contract() {
    let (store, sweep) =
        common::store_with_finished_sweep("contract", &common::small_sweep()).await;
    let doc = common::get_json(&store, "/api/openapi.json").await;
    assert_eq!(doc["openapi"], "3.1.0");
    let real = real_values(&store, sweep).await;
    assert!(real.hashes.len() == 2 && !real.sweep_figures.is_empty());
    let ops = operations(&doc);
    let mut run = Run {
        store,
        gen: Gen {
            rng: ChaCha8Rng::seed_from_u64(SEED),
            doc: doc.clone(),
            schemas: Schemas::new(doc["components"].clone()),
        },
        real,
        seen: BTreeMap::new(),
    };
    check_schemas(&doc["paths"], &mut run.gen.schemas);
    check_schemas(&doc["components"], &mut run.gen.schemas);
    let started = std::time::Instant::now();
    let mut sent = 0;
    for _ in 0..ROUNDS {
        sent += run.round(&ops).await;
    }
    println!(
        "{sent} generated requests over {} operations in {:.1} s",
        ops.len(),
        started.elapsed().as_secs_f64()
    );
    for (op, statuses) in &run.seen {
        println!("{op}: {statuses:?}");
    }
    // Every operation was answered with success at least once, so that
    // no operation is left unchecked by a generator that never reaches it.
    for op in &ops {
        let answered = run.seen.get(&op.name()).cloned().unwrap_or_default();
        assert!(
            answered.keys().any(|s| (200..300).contains(s)),
            "{} never succeeded: {answered:?}",
            op.name()
        );
    }
}
