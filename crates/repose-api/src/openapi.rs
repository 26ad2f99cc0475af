//! The OpenAPI 3.1 description of the API, served at `/api/openapi.json`.

use serde_json::{json, Value};

fn error_responses() -> Value {
    json!({
        "400": { "$ref": "#/components/responses/Error" },
        "404": { "$ref": "#/components/responses/Error" },
        "422": { "$ref": "#/components/responses/Error" }
    })
}

fn ok(description: &str, schema: Value) -> Value {
    json!({ "description": description, "content": { "application/json": { "schema": schema } } })
}

fn id_param() -> Value {
    json!({ "name": "id", "in": "path", "required": true, "schema": { "type": "string", "format": "uuid" } })
}

fn format_param() -> Value {
    json!({ "name": "format", "in": "query", "required": false,
            "schema": { "type": "string", "enum": ["json", "csv"], "default": "json" } })
}

fn with_errors(mut responses: Value) -> Value {
    if let (Some(r), Some(e)) = (responses.as_object_mut(), error_responses().as_object()) {
        for (k, v) in e {
            r.entry(k.clone()).or_insert(v.clone());
        }
    }
    responses
}

pub fn document() -> Value {
    let aggregate = json!({
        "type": "object",
        "properties": {
            "n": { "type": "integer" },
            "mean": { "type": ["number", "null"] },
            "sd": { "type": ["number", "null"], "description": "sample standard deviation (n − 1), the paper's error bar" },
            "sem": { "type": ["number", "null"], "description": "standard error of the mean" }
        }
    });
    json!({
        "openapi": "3.1.0",
        "info": {
            "title": "repose",
            "version": env!("CARGO_PKG_VERSION"),
            "description": "Parameter studies of granular piles (Lee & Herrmann 1993): sweeps of scenes, \
                            per-sample angles and per-point statistics for the paper's figures."
        },
        "paths": {
            "/api/health": { "get": { "summary": "Service and database status",
                "responses": { "200": ok("alive", json!({ "type": "object" })) } } },
            "/api/sweeps": {
                "get": { "summary": "List sweeps with progress and ETA",
                    "responses": { "200": ok("sweeps", json!({ "type": "object",
                        "properties": { "sweeps": { "type": "array", "items": { "$ref": "#/components/schemas/Sweep" } } } })) } },
                "post": { "summary": "Queue a sweep",
                    "requestBody": { "required": true, "content": { "application/json": {
                        "schema": { "$ref": "#/components/schemas/SweepSpec" } } } },
                    "responses": with_errors(json!({ "201": ok("created", json!({ "type": "object", "properties": {
                        "id": { "type": "string" }, "jobs": { "type": "integer" },
                        "reused": { "type": "integer", "description": "jobs whose sample was already computed" },
                        "queued": { "type": "integer" }, "message": { "type": "string" } } })) })) }
            },
            "/api/sweeps/{id}": { "get": { "summary": "One sweep with progress counts and ETA",
                "parameters": [id_param()],
                "responses": with_errors(json!({ "200": ok("the sweep", json!({ "$ref": "#/components/schemas/Sweep" })) })) } },
            "/api/sweeps/{id}/cancel": { "post": { "summary": "Cancel a sweep: queued jobs are dropped, running ones stop at their next heartbeat",
                "parameters": [id_param()],
                "responses": with_errors(json!({ "200": ok("the cancelled sweep", json!({ "$ref": "#/components/schemas/Sweep" })) })) } },
            "/api/sweeps/{id}/samples": { "get": { "summary": "Per-sample results (JSON or CSV)",
                "parameters": [id_param(), format_param()],
                "responses": with_errors(json!({ "200": ok("samples", json!({ "type": "object" })) })) } },
            "/api/sweeps/{id}/points": { "get": { "summary": "Per-point n, mean, sd and sem of every angle (JSON or CSV)",
                "parameters": [id_param(), format_param()],
                "responses": with_errors(json!({ "200": ok("points", json!({ "type": "object", "properties": {
                    "points": { "type": "array", "items": { "$ref": "#/components/schemas/Point" } } } })) })) } },
            "/api/sweeps/{id}/series": { "get": { "summary": "Any x / series / y choice over a sweep's axes",
                "parameters": [id_param(),
                    { "name": "x", "in": "query", "required": true, "schema": { "type": "string" }, "description": "a swept scene key, e.g. contact.mu" },
                    { "name": "series", "in": "query", "required": false, "schema": { "type": "string" } },
                    { "name": "y", "in": "query", "required": false, "schema": { "type": "string", "default": "theta_r" } }],
                "responses": with_errors(json!({ "200": ok("series", json!({ "$ref": "#/components/schemas/Series" })) })) } },
            "/api/sweeps/{id}/figures/{figure}": { "get": { "summary": "The paper's figures 2a, 2b, 3 and 4 as series",
                "parameters": [id_param(), { "name": "figure", "in": "path", "required": true,
                    "schema": { "type": "string", "enum": ["2a", "2b", "3", "4"] } }],
                "responses": with_errors(json!({ "200": ok("series", json!({ "$ref": "#/components/schemas/Series" })) })) } },
            "/api/figures": { "get": { "summary": "The figures and metrics the service knows",
                "responses": { "200": ok("figures", json!({ "type": "object" })) } } },
            "/api/samples/{hash}": { "get": { "summary": "The full run report of one sample (final state, energy trace, scene)",
                "parameters": [{ "name": "hash", "in": "path", "required": true, "schema": { "type": "string" } }],
                "responses": with_errors(json!({ "200": ok("run report", json!({ "type": "object" })) })) } },
            "/docs/{file}": { "get": { "summary": "A generated report file (reproduction.md, speed-vs-accuracy.md and their SVG, CSV and JSON files)",
                "parameters": [{ "name": "file", "in": "path", "required": true, "schema": { "type": "string" } }],
                "responses": { "200": { "description": "the file (Markdown, SVG, CSV or JSON)" },
                               "404": { "$ref": "#/components/responses/Error" } } } }
        },
        "components": {
            "responses": {
                "Error": { "description": "the request cannot be served", "content": { "application/json": {
                    "schema": { "$ref": "#/components/schemas/Error" } } } }
            },
            "schemas": {
                "Error": { "type": "object", "required": ["error", "errors"], "properties": {
                    "error": { "type": "string" },
                    "errors": { "type": "array", "items": { "type": "object", "properties": {
                        "field": { "type": "string", "description": "dotted path of the field at fault" },
                        "message": { "type": "string" } } } } } },
                "SweepSpec": { "type": "object", "required": ["protocol"], "additionalProperties": false, "properties": {
                    "name": { "type": "string" },
                    "protocol": { "type": "string", "enum": ["fill_release", "tilt", "flux", "free_run"] },
                    "base": { "type": "object", "description": "scene values shared by every job (see docs/scene.md)" },
                    "axes": { "type": "object", "additionalProperties": { "type": "array", "minItems": 1 },
                              "description": "values to sweep, by dotted scene key" },
                    "samples": { "type": "integer", "minimum": 1, "default": 1 },
                    "fidelity": { "type": "string", "enum": ["quick", "standard", "paper"], "default": "standard" },
                    "seed_base": { "type": "integer", "minimum": 0, "default": 0 },
                    "priority": { "type": "integer", "default": 0 } } },
                "Sweep": { "type": "object", "properties": {
                    "id": { "type": "string" }, "name": { "type": "string" }, "protocol": { "type": "string" },
                    "priority": { "type": "integer" }, "state": { "type": "string", "enum": ["active", "cancelled"] },
                    "created_at": { "type": "integer", "description": "unix milliseconds" },
                    "spec": { "$ref": "#/components/schemas/SweepSpec" },
                    "progress": { "type": "object", "properties": {
                        "queued": { "type": "integer" }, "running": { "type": "integer" }, "done": { "type": "integer" },
                        "failed": { "type": "integer" }, "cancelled": { "type": "integer" } } },
                    "eta_seconds": { "type": ["number", "null"] },
                    "cost": { "type": "object", "description": "what the finished samples took", "properties": {
                        "samples": { "type": "integer" },
                        "wall_time": { "type": "number", "description": "sum of the samples' run times, s (one core each)" },
                        "particle_steps": { "type": "integer", "description": "sum of grains × steps" } } } } },
                "Aggregate": aggregate,
                "Point": { "type": "object", "properties": {
                    "point": { "type": "object" }, "samples": { "type": "integer" },
                    "failures": { "type": "integer", "description": "samples that ended without a result" },
                    "metrics": { "type": "object", "additionalProperties": { "$ref": "#/components/schemas/Aggregate" } } } },
                "Series": { "type": "object", "properties": {
                    "x": { "type": "string" }, "series": { "type": ["string", "null"] }, "y": { "type": "string" },
                    "points": { "type": "array", "items": { "type": "object", "properties": {
                        "x": {}, "series": {}, "n": { "type": "integer" }, "mean": { "type": ["number", "null"] },
                        "sd": { "type": ["number", "null"] }, "sem": { "type": ["number", "null"] },
                        "failures": { "type": "integer" } } } } } }
            }
        }
    })
}
