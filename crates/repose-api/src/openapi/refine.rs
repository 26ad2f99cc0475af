//! What the derived document cannot say by itself, stated here so that the
//! document is exactly what the server takes and answers:
//!
//! * the names the registries accept, as enums built from the registries
//!   themselves (protocols, presets, metrics and their phases, models,
//!   papers with their sweeps and figures, report and page files);
//! * what the handlers require or refuse: required query parameters, empty
//!   values, bounds on counts, keys a sweep sets itself, rules between
//!   fields of a sweep;
//! * the shape of axis values, which may be any JSON value a scene key
//!   takes (numbers, strings, booleans, lists such as gravity vectors,
//!   whole sections, or null for "the default");
//! * every status each route answers with.
//!
//! What only the physics can check (whether a scene key exists for the
//! protocol, whether a value is in range) stays a 422 naming the field;
//! the document gives examples that pass those checks.
//!
//! Every edit names the place it changes and panics if the derived
//! document lacks it, so a renamed type or field fails the crate's tests
//! instead of leaving a stale contract.

use repose_physics::{registry, Preset};
use repose_store::Backend;
use repose_studies::papers::PAPERS;
use repose_sweeps::spec::MAX_JOBS;
use serde_json::{json, Value};

/// Names the registries accept.
struct Registry {
    protocols: Vec<&'static str>,
    presets: Vec<&'static str>,
    /// Every metric of every protocol, each once, in registry order.
    metrics: Vec<&'static str>,
    phases: Vec<&'static str>,
    models: Vec<&'static str>,
    dimensions: Vec<usize>,
    papers: Vec<&'static str>,
    /// Study sweep keys of every paper, each once.
    study_sweeps: Vec<String>,
    /// Figure keys of every paper, each once.
    figures: Vec<String>,
    docs: Vec<String>,
    web: Vec<&'static str>,
}

fn push_new<T: PartialEq>(list: &mut Vec<T>, item: T) {
    if !list.contains(&item) {
        list.push(item);
    }
}

impl Registry {
    fn gather() -> Registry {
        let mut r = Registry {
            protocols: registry::protocol_names(),
            presets: Preset::ALL.iter().map(|p| p.name()).collect(),
            metrics: Vec::new(),
            phases: Vec::new(),
            models: registry::model_names(),
            dimensions: Vec::new(),
            papers: PAPERS.iter().map(|p| p.key).collect(),
            study_sweeps: Vec::new(),
            figures: Vec::new(),
            docs: crate::doc_names(),
            web: crate::WEB.iter().map(|(name, _, _)| *name).collect(),
        };
        for p in registry::protocols() {
            for m in p.metrics() {
                push_new(&mut r.metrics, m.name);
                push_new(&mut r.phases, m.phase);
            }
            for d in p.dimensions() {
                push_new(&mut r.dimensions, *d);
            }
        }
        r.dimensions.sort_unstable();
        for p in PAPERS {
            for s in (p.sweeps)() {
                push_new(&mut r.study_sweeps, s.key.to_string());
            }
            for f in (p.figures)() {
                push_new(&mut r.figures, f.key.to_string());
            }
        }
        r
    }
}

fn names<T: serde::Serialize>(list: &[T]) -> Value {
    json!(list)
}

/// The value at `pointer`; the document must have it.
fn at<'a>(doc: &'a mut Value, pointer: &str) -> &'a mut Value {
    doc.pointer_mut(pointer)
        .unwrap_or_else(|| panic!("the derived OpenAPI document has nothing at {pointer}"))
}

/// A property of a component schema, looked up in its `allOf` parts too.
fn property<'a>(doc: &'a mut Value, schema: &str, name: &str) -> &'a mut Value {
    let base = format!("/components/schemas/{schema}");
    let direct = format!("{base}/properties/{name}");
    if doc.pointer(&direct).is_some() {
        return at(doc, &direct);
    }
    let parts = doc
        .pointer(&format!("{base}/allOf"))
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    let found = (0..parts)
        .map(|i| format!("{base}/allOf/{i}/properties/{name}"))
        .find(|p| doc.pointer(p).is_some())
        .unwrap_or(direct);
    at(doc, &found)
}

/// Adds (or replaces) the keys of `extra` in the object `target`.
fn merge(target: &mut Value, extra: Value) {
    let (Some(target), Value::Object(extra)) = (target.as_object_mut(), extra) else {
        panic!("only objects are merged");
    };
    target.extend(extra);
}

/// Replaces a schema, keeping its description.
fn replace(target: &mut Value, with: Value) {
    let description = target.get("description").cloned();
    *target = with;
    if let Some(d) = description {
        merge(target, json!({ "description": d }));
    }
}

fn reference(name: &str) -> Value {
    json!({ "$ref": format!("#/components/schemas/{name}") })
}

/// One operation, by method and path template.
fn operation<'a>(doc: &'a mut Value, method: &str, path: &str) -> &'a mut Value {
    let escaped = path.replace('~', "~0").replace('/', "~1");
    at(doc, &format!("/paths/{escaped}/{method}"))
}

/// One parameter of an operation.
fn parameter<'a>(doc: &'a mut Value, method: &str, path: &str, name: &str) -> &'a mut Value {
    operation(doc, method, path)["parameters"]
        .as_array_mut()
        .and_then(|ps| ps.iter_mut().find(|p| p["name"] == name))
        .unwrap_or_else(|| panic!("{method} {path} has no parameter `{name}`"))
}

pub(super) fn apply(doc: &mut Value) {
    let reg = Registry::gather();
    axis_schemas(doc);
    registry_schemas(doc, &reg);
    study_schemas(doc, &reg);
    sweep_spec(doc, &reg);
    sweep_rules(doc);
    queue_request(doc, &reg);
    path_parameters(doc, &reg);
    query_parameters(doc, &reg);
    statuses(doc);
}

/// Axis values and the maps of them: what sweeps take and points carry.
fn axis_schemas(doc: &mut Value) {
    let schemas = at(doc, "/components/schemas");
    merge(
        schemas,
        json!({
            "AxisValue": {
                "description": "A value of a swept scene key: a number, a string, a boolean, a list \
                    (a gravity vector, say), a whole section, or null for the key's default.",
                "type": ["number", "string", "boolean", "array", "object", "null"]
            },
            "SceneKey": {
                "description": "A dotted scene key such as `contact.mu`; `protocol`, `seed` and \
                    `preset` are set by the sweep itself.",
                "type": "string",
                "pattern": "^[^.]+(\\.[^.]+)*$",
                "not": { "enum": ["protocol", "seed", "preset"] }
            },
            "Axes": {
                "description": "Values to sweep, by dotted scene key; each axis has at least one value.",
                "type": "object",
                "propertyNames": reference("SceneKey"),
                "additionalProperties": {
                    "type": "array", "minItems": 1, "items": reference("AxisValue")
                }
            },
            "PointValues": {
                "description": "The axis values of one point, by dotted scene key.",
                "type": "object",
                "additionalProperties": reference("AxisValue")
            }
        }),
    );
    for schema in ["StudySweep", "Reduced", "SweepSpec"] {
        replace(property(doc, schema, "axes"), reference("Axes"));
    }
    for schema in ["Point", "Sample"] {
        replace(property(doc, schema, "point"), reference("PointValues"));
    }
    for (schema, field) in [
        ("SeriesPoint", "x"),
        ("SeriesPoint", "series"),
        ("FitData", "series_value"),
        ("SeriesData", "series_value"),
    ] {
        replace(property(doc, schema, field), reference("AxisValue"));
    }
}

/// Enums from the registries in what the registry routes answer, and
/// the fixed values of the service's own answers.
fn registry_schemas(doc: &mut Value, reg: &Registry) {
    merge(
        property(doc, "ProtocolInfo", "name"),
        json!({ "enum": names(&reg.protocols) }),
    );
    merge(
        property(doc, "ProtocolInfo", "models"),
        json!({ "items": { "type": "string", "enum": names(&reg.models) } }),
    );
    merge(
        property(doc, "ProtocolInfo", "dimensions"),
        json!({ "items": { "type": "integer", "enum": names(&reg.dimensions) } }),
    );
    merge(
        property(doc, "ProtocolInfo", "presets"),
        json!({ "propertyNames": { "enum": names(&reg.presets) } }),
    );
    merge(
        property(doc, "MetricInfo", "name"),
        json!({ "enum": names(&reg.metrics) }),
    );
    merge(
        property(doc, "MetricInfo", "phase"),
        json!({ "enum": names(&reg.phases) }),
    );
    let backends: Vec<String> = [Backend::Sqlite, Backend::Postgres]
        .into_iter()
        .map(crate::backend_name)
        .collect();
    merge(
        property(doc, "Health", "database"),
        json!({ "enum": backends }),
    );
    merge(property(doc, "Health", "status"), json!({ "enum": ["ok"] }));
    merge(
        property(doc, "Comparison", "verdict"),
        json!({ "enum": ["agrees", "differs", "not resolved", "no result"] }),
    );
    replace(
        property(doc, "Queued", "links"),
        json!({
            "type": "object",
            "properties": { "self": { "type": "string", "description": "the sweep's own route" } },
            "required": ["self"]
        }),
    );
}

/// Paper, sweep and figure keys in the study answers.
fn study_schemas(doc: &mut Value, reg: &Registry) {
    let papers = json!({ "enum": names(&reg.papers) });
    let sweeps = json!({ "enum": names(&reg.study_sweeps) });
    let figures = json!({ "enum": names(&reg.figures) });
    for (schema, field, values) in [
        ("PaperSummary", "key", &papers),
        ("StudySweep", "key", &sweeps),
        ("FigureSummary", "key", &figures),
        ("FigureRef", "paper", &papers),
        ("FigureRef", "figure", &figures),
        ("FigureData", "paper", &papers),
        ("FigureData", "figure", &figures),
    ] {
        merge(property(doc, schema, field), values.clone());
    }
    merge(
        property(doc, "FigureSummary", "sweeps"),
        json!({ "items": { "type": "string", "enum": names(&reg.study_sweeps) } }),
    );
    merge(
        property(doc, "StudySweep", "protocol"),
        json!({ "enum": names(&reg.protocols) }),
    );
    merge(
        property(doc, "ComparisonAnswer", "sweeps"),
        json!({ "propertyNames": { "enum": names(&reg.study_sweeps) } }),
    );
    merge(
        property(doc, "FigureData", "sweeps"),
        json!({ "propertyNames": { "enum": names(&reg.study_sweeps) } }),
    );
}

/// Bounds and names of a sweep's fields, with examples that every
/// protocol but those needing more (see [`needs`]) accepts.
fn sweep_spec(doc: &mut Value, reg: &Registry) {
    let largest = MAX_JOBS as u64;
    let mut metrics = names(&reg.metrics);
    if let Value::Array(list) = &mut metrics {
        list.push(Value::Null);
    }
    for (field, extra) in [
        ("protocol", json!({ "enum": names(&reg.protocols) })),
        (
            "fidelity",
            json!({ "enum": names(&reg.presets), "default": "standard" }),
        ),
        (
            "samples",
            json!({ "minimum": 1, "maximum": largest, "default": 1, "examples": [1, 2, 3] }),
        ),
        (
            "max_samples",
            json!({ "minimum": 2, "maximum": largest, "examples": [4, 10] }),
        ),
        (
            "target_sem",
            json!({ "exclusiveMinimum": 0, "examples": [0.5, 2.0] }),
        ),
        ("target_metric", json!({ "enum": metrics })),
        ("seed_base", json!({ "maximum": i64::MAX - 1 })),
        (
            "base",
            json!({
                "description": "Scene values shared by every job: any key of the scene document \
                    except `protocol`, `seed` and `preset`, which the sweep sets itself.",
                "propertyNames": { "not": { "enum": ["protocol", "seed", "preset"] } },
                "examples": [{}, { "rng": "chacha8" }, { "numerics": { "max_overlap": 0.4 } }]
            }),
        ),
        (
            "axes",
            json!({ "examples": [
                { "numerics.dt_factor": [0.01, 0.02] },
                { "numerics.integrator": ["gear5", "verlet"] },
                {}
            ] }),
        ),
    ] {
        merge(property(doc, "SweepSpec", field), extra);
    }
    let about = format!(
        "A sweep: a protocol, a base scene, axes and samples. The scenes it expands into are \
         checked by the physics, which refuses unknown keys and values out of range with 422 \
         naming the field; a sweep expands into at most {MAX_JOBS} jobs."
    );
    merge(
        at(doc, "/components/schemas/SweepSpec"),
        json!({ "description": about }),
    );
}

/// What a protocol needs in its base scene beyond the defaults (its scene
/// keys), with a base that gives it.
fn needs() -> Vec<(&'static str, &'static [&'static str], Value)> {
    vec![(
        "free_run",
        &["particles", "duration"],
        json!({ "duration": 0.01, "particles": [{ "position": [0.0, 0.05], "radius": 0.01 }] }),
    )]
}

/// Rules between fields of a sweep, as `if`/`then` parts: the metrics a
/// protocol's `target_metric` may name, the base a protocol needs, and the
/// fields that go with `target_sem`.
fn sweep_rules(doc: &mut Value) {
    let mut rules = Vec::new();
    for p in registry::protocols() {
        let when = json!({ "properties": { "protocol": { "const": p.name() } }, "required": ["protocol"] });
        let mut metrics: Vec<Value> = p.metrics().iter().map(|m| json!(m.name)).collect();
        let then = if metrics.is_empty() {
            let none = json!({ "type": "null" });
            json!({ "properties": { "target_sem": none, "target_metric": none, "max_samples": none } })
        } else {
            metrics.push(Value::Null);
            json!({ "properties": { "target_metric": { "enum": metrics } } })
        };
        rules.push(json!({ "if": when, "then": then }));
        if let Some((_, keys, example)) = needs().into_iter().find(|(name, _, _)| *name == p.name())
        {
            rules.push(json!({
                "if": when,
                "then": {
                    "required": ["base"],
                    "properties": { "base": { "required": keys, "examples": [example] } }
                }
            }));
        }
    }
    for field in ["target_metric", "max_samples"] {
        rules.push(json!({
            "if": { "properties": { field: { "not": { "type": "null" } } }, "required": [field] },
            "then": {
                "required": ["target_sem"],
                "properties": { "target_sem": { "type": "number" } }
            }
        }));
    }
    merge(
        at(doc, "/components/schemas/SweepSpec"),
        json!({ "allOf": rules }),
    );
}

fn queue_request(doc: &mut Value, reg: &Registry) {
    let mut presets = names(&reg.presets);
    if let Value::Array(list) = &mut presets {
        list.push(Value::Null);
    }
    merge(
        property(doc, "QueueRequest", "fidelity"),
        json!({ "enum": presets }),
    );
    operation(doc, "post", "/api/studies/{paper}/sweeps/{key}")["requestBody"]["required"] =
        json!(false);
    merge(
        property(doc, "QueueRequest", "samples"),
        json!({ "minimum": 1, "maximum": MAX_JOBS as u64, "examples": [1, 2] }),
    );
}

/// Path parameters: the keys the registries know, and what the store's
/// ids look like.
fn path_parameters(doc: &mut Value, reg: &Registry) {
    let paper = json!({ "type": "string", "enum": names(&reg.papers) });
    let figure = json!({ "type": "string", "enum": names(&reg.figures) });
    let id = json!({ "type": "string", "minLength": 1 });
    for (method, path, name, schema) in [
        (
            "get",
            "/static/{file}",
            "file",
            json!({ "type": "string", "enum": names(&reg.web) }),
        ),
        (
            "get",
            "/docs/{file}",
            "file",
            json!({ "type": "string", "enum": names(&reg.docs) }),
        ),
        ("get", "/api/studies/{paper}", "paper", paper.clone()),
        (
            "post",
            "/api/studies/{paper}/sweeps/{key}",
            "paper",
            paper.clone(),
        ),
        (
            "post",
            "/api/studies/{paper}/sweeps/{key}",
            "key",
            json!({ "type": "string", "enum": names(&reg.study_sweeps) }),
        ),
        (
            "get",
            "/api/studies/{paper}/figures/{figure}",
            "paper",
            paper.clone(),
        ),
        (
            "get",
            "/api/studies/{paper}/figures/{figure}",
            "figure",
            figure.clone(),
        ),
        (
            "get",
            "/api/studies/{paper}/comparison",
            "paper",
            paper.clone(),
        ),
        (
            "get",
            "/api/sweeps/{id}/figures/{paper}/{figure}",
            "paper",
            paper.clone(),
        ),
        (
            "get",
            "/api/sweeps/{id}/figures/{paper}/{figure}",
            "figure",
            figure.clone(),
        ),
        ("get", "/api/samples/{hash}", "hash", id.clone()),
    ] {
        parameter(doc, method, path, name)["schema"] = schema;
    }
    let ids = doc["paths"]
        .as_object_mut()
        .into_iter()
        .flat_map(|paths| paths.values_mut())
        .flat_map(|item| {
            item.as_object_mut()
                .into_iter()
                .flat_map(|ops| ops.values_mut())
        })
        .filter_map(|op| op.get_mut("parameters").and_then(Value::as_array_mut))
        .flatten()
        .filter(|p| p["name"] == "id" && p["in"] == "path");
    for p in ids {
        p["schema"] = id.clone();
        p["description"] = json!("a sweep's id, as its creation answered");
    }
}

/// Query parameters: never null, and what the handlers require of them.
fn query_parameters(doc: &mut Value, reg: &Registry) {
    for path in ["/api/sweeps/{id}/samples", "/api/sweeps/{id}/points"] {
        parameter(doc, "get", path, "format")["schema"] =
            json!({ "type": "string", "enum": ["json", "csv"], "default": "json" });
        merge(
            at(operation(doc, "get", path), "/responses/200/content"),
            json!({ "text/csv": { "schema": { "type": "string" } } }),
        );
    }
    let series = "/api/sweeps/{id}/series";
    let x = parameter(doc, "get", series, "x");
    x["required"] = json!(true);
    x["schema"] = json!({ "type": "string", "minLength": 1, "examples": ["contact.mu"] });
    parameter(doc, "get", series, "series")["schema"] =
        json!({ "type": "string", "minLength": 1, "examples": ["contact.mu"] });
    parameter(doc, "get", series, "y")["schema"] =
        json!({ "type": "string", "enum": names(&reg.metrics), "examples": ["theta_r"] });
    let bindings = json!({
        "type": "string",
        "pattern": "^[^,:]*:[^,]*(,[^,:]*:[^,]*)*$",
        "examples": ["fig347:0f8fad5b-d9cb-469f-a165-70867728950e"]
    });
    for path in [
        "/api/studies/{paper}/figures/{figure}",
        "/api/studies/{paper}/comparison",
    ] {
        parameter(doc, "get", path, "sweeps")["schema"] = bindings.clone();
    }
}

/// The answers every route may give beyond its own: a missing token, a
/// failing database, an oversized body, a timeout or a failing handler;
/// and a description for every answer.
fn statuses(doc: &mut Value) {
    merge(
        at(doc, "/components"),
        json!({ "securitySchemes": { "token": {
            "type": "http", "scheme": "bearer",
            "description": "The server's access token, when it has one: needed to change the store, \
                and on a private server to read it."
        } } }),
    );
    let Some(paths) = doc["paths"].as_object_mut() else {
        return;
    };
    for (path, item) in paths.iter_mut() {
        let Some(ops) = item.as_object_mut() else {
            continue;
        };
        let guarded = path.starts_with("/api/") && path != "/api/health";
        let stored = path.starts_with("/api/sweeps")
            || path.starts_with("/api/samples")
            || path.starts_with("/api/studies/{paper}/")
            || path == "/api/health";
        for op in ops.values_mut() {
            let has_body = op.get("requestBody").is_some();
            if guarded {
                op["security"] = json!([{}, { "token": [] }]);
            }
            let responses = &mut op["responses"];
            if guarded {
                error(
                    responses,
                    "401",
                    "the server has an access token and the request does not carry it",
                );
            }
            if stored {
                error(responses, "503", "the database failed");
            }
            if has_body {
                error(responses, "413", "the body is larger than 2 MiB");
            }
            error(
                responses,
                "default",
                "408 when the request outlasts the server's time limit, 500 when the server fails on it",
            );
            describe(responses);
        }
    }
}

/// Declares an error answer with the usual body, unless already declared.
fn error(responses: &mut Value, status: &str, description: &str) {
    if responses.get(status).is_none() {
        responses[status] = json!({
            "description": description,
            "content": { "application/json": { "schema": reference("ErrorBody") } }
        });
    }
}

/// Fills the descriptions the derived document leaves empty.
fn describe(responses: &mut Value) {
    let Some(map) = responses.as_object_mut() else {
        return;
    };
    for (status, response) in map.iter_mut() {
        if response["description"]
            .as_str()
            .is_some_and(|d| !d.is_empty())
        {
            continue;
        }
        response["description"] = json!(match status.as_str() {
            "200" => "the answer",
            "201" => "the sweep was queued",
            "400" => "the request cannot be read: a missing or malformed parameter or body",
            "404" => "no such route, id or key",
            "409" => "the request conflicts with the sweep's state",
            "422" => "the request is refused; `errors` names each field at fault",
            _ => "an answer",
        });
    }
}
