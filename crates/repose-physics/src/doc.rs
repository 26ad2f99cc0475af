//! Scene documents as JSON trees, and the one way to address a value in
//! them: a dotted path such as `contact.mu`.
//!
//! A scene is written as TOML or JSON; either way it becomes a
//! [`serde_json::Map`] here. Command-line overrides (`--set contact.mu=0.3`),
//! the axes of a sweep and the settings of a fidelity preset all set values
//! through [`set`], so they agree on what a path means and refuse the same
//! mistakes with the same message.

use serde_json::{Map, Value};

/// A JSON object: a scene document or one of its sections.
pub type Doc = Map<String, Value>;

/// Why a document or an assignment cannot be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DocError {
    /// The path at fault (`(document)` for the whole text).
    pub field: String,
    pub message: String,
}

impl DocError {
    fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        DocError {
            field: field.into(),
            message: message.into(),
        }
    }
}

/// Reads a TOML document, or a JSON one (text starting with `{`). JSON
/// `null` means "not set" and is dropped, as TOML has no null.
pub fn parse(text: &str) -> Result<Doc, DocError> {
    let value = if text.trim_start().starts_with('{') {
        serde_json::from_str::<Value>(text)
            .map_err(|e| DocError::new("(document)", format!("not valid JSON: {e}")))?
    } else {
        let table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| DocError::new("(document)", e.to_string()))?;
        from_toml(toml::Value::Table(table), "")?
    };
    match drop_nulls(value) {
        Value::Object(doc) => Ok(doc),
        _ => Err(DocError::new("(document)", "a scene is a table of keys")),
    }
}

/// Splits `key=value` and reads the value as a TOML value (`0.3`, `true`,
/// `"gear5"`, `[0, -981]`, `{ width = 2 }`); anything else is taken as a plain
/// string, so `numerics.integrator=verlet` needs no quotes.
pub fn parse_assignment(assignment: &str) -> Result<(String, Value), DocError> {
    let Some((key, raw)) = assignment.split_once('=') else {
        return Err(DocError::new(
            shown_key(assignment),
            "an override is written key=value, e.g. contact.mu=0.3",
        ));
    };
    let (key, raw) = (key.trim(), raw.trim());
    check_path(key)?;
    let value = match format!("v = {raw}").parse::<toml::Table>() {
        Ok(mut t) => match t.remove("v") {
            Some(v) => from_toml(v, key)?,
            None => Value::String(raw.to_string()),
        },
        Err(_) => Value::String(raw.to_string()),
    };
    Ok((key.to_string(), value))
}

/// A TOML value as JSON. TOML can write `nan` and `inf`, which JSON cannot
/// hold (they would become null, read as "not set", and so quietly the
/// default): they are refused, naming the path (`box.width`, `gravity[1]`).
fn from_toml(value: toml::Value, path: &str) -> Result<Value, DocError> {
    Ok(match value {
        toml::Value::Float(x) if !x.is_finite() => {
            return Err(DocError::new(
                shown_key(path),
                format!("{x} is not a finite number"),
            ))
        }
        toml::Value::Table(t) => Value::Object(
            t.into_iter()
                .map(|(k, v)| {
                    let inner = if path.is_empty() {
                        k.clone()
                    } else {
                        format!("{path}.{k}")
                    };
                    Ok((k, from_toml(v, &inner)?))
                })
                .collect::<Result<Map<_, _>, DocError>>()?,
        ),
        toml::Value::Array(items) => Value::Array(
            items
                .into_iter()
                .enumerate()
                .map(|(i, v)| from_toml(v, &format!("{path}[{i}]")))
                .collect::<Result<_, _>>()?,
        ),
        other => serde_json::to_value(other)
            .map_err(|e| DocError::new(shown_key(path), e.to_string()))?,
    })
}

fn check_path(key: &str) -> Result<(), DocError> {
    if key.is_empty() || key.split('.').any(str::is_empty) {
        return Err(DocError::new(shown_key(key), "empty segment in the key"));
    }
    Ok(())
}

/// Sets `a.b.c = value`, creating tables on the way. Fails, naming the
/// path, where a segment on the way is set to something that is not a table.
pub fn set(doc: &mut Doc, key: &str, value: Value) -> Result<(), DocError> {
    check_path(key)?;
    let parts: Vec<&str> = key.split('.').collect();
    let Some((last, on_the_way)) = parts.split_last() else {
        return Err(DocError::new(key, "empty key"));
    };
    let mut table = doc;
    for (k, part) in on_the_way.iter().enumerate() {
        let entry = table
            .entry(part.to_string())
            .or_insert_with(|| Value::Object(Map::new()));
        if entry.is_null() {
            *entry = Value::Object(Map::new());
        }
        table = match entry {
            Value::Object(t) => t,
            other => {
                return Err(DocError::new(
                    parts[..=k].join("."),
                    format!("is {}, not a table, so `{key}` cannot be set", kind(other)),
                ))
            }
        };
    }
    table.insert(last.to_string(), value);
    Ok(())
}

/// The value at a dotted path, if it is set (and not null).
pub fn get<'a>(doc: &'a Doc, key: &str) -> Option<&'a Value> {
    let mut parts = key.split('.');
    let mut value = doc.get(parts.next()?)?;
    for part in parts {
        value = value.as_object()?.get(part)?;
    }
    (!value.is_null()).then_some(value)
}

/// Whether a dotted path is set.
pub fn has(doc: &Doc, key: &str) -> bool {
    get(doc, key).is_some()
}

/// Fills in `defaults` wherever `doc` leaves a key unset, table by table.
pub fn merge_defaults(doc: &mut Doc, defaults: &Doc) {
    for (key, default) in defaults {
        match (doc.get_mut(key), default) {
            (None, _) => {
                doc.insert(key.clone(), default.clone());
            }
            (Some(Value::Object(mine)), Value::Object(theirs)) => merge_defaults(mine, theirs),
            (Some(_), _) => {}
        }
    }
}

/// A short name for the kind of a JSON value, for messages.
pub fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "a table",
    }
}

/// JSON `null` means "not set"; such keys are dropped.
pub fn drop_nulls(v: Value) -> Value {
    match v {
        Value::Object(m) => Value::Object(
            m.into_iter()
                .filter(|(_, v)| !v.is_null())
                .map(|(k, v)| (k, drop_nulls(v)))
                .collect(),
        ),
        Value::Array(a) => Value::Array(a.into_iter().map(drop_nulls).collect()),
        other => other,
    }
}

/// A field's path as errors show it: an empty key is named as such.
pub(crate) fn shown_key(field: &str) -> String {
    if field.is_empty() {
        "(empty key)".into()
    } else {
        field.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn doc(v: Value) -> Doc {
        v.as_object().cloned().unwrap()
    }

    #[test]
    fn toml_and_json_documents_read_alike() {
        let a = parse("protocol = \"tilt\"\n[contact]\nmu = 0.3").unwrap();
        let b = parse(r#"{"protocol": "tilt", "contact": {"mu": 0.3, "k_s": null}}"#).unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn assignments_read_toml_values_or_plain_words() {
        assert_eq!(
            parse_assignment("contact.mu=0.3").unwrap(),
            ("contact.mu".into(), json!(0.3))
        );
        assert_eq!(
            parse_assignment("numerics.integrator = verlet").unwrap().1,
            json!("verlet")
        );
        assert_eq!(
            parse_assignment("gravity=[0, -981]").unwrap().1,
            json!([0, -981])
        );
        assert_eq!(
            parse_assignment("contact.mu").unwrap_err().field,
            "contact.mu"
        );
        assert_eq!(parse_assignment("a..b=1").unwrap_err().field, "a..b");
    }

    #[test]
    fn a_number_that_is_not_finite_is_refused_by_its_path() {
        let err = parse("protocol = \"tilt\"\n[box]\nwidth = nan").unwrap_err();
        assert_eq!(err.field, "box.width");
        assert!(
            err.message.contains("not a finite number"),
            "{}",
            err.message
        );
        let err = parse("gravity = [0.0, -inf]").unwrap_err();
        assert_eq!(err.field, "gravity[1]");
        let err =
            parse("[[walls]]\nnormal = [0.0, 1.0]\n[[walls]]\nnormal = [+inf, 0.0]").unwrap_err();
        assert_eq!(err.field, "walls[1].normal[0]");
        let err = parse_assignment("contact.mu=inf").unwrap_err();
        assert_eq!(err.field, "contact.mu");
        // Finite numbers, and the words nan and inf as strings, still read.
        assert_eq!(parse("w = 1e308").unwrap()["w"], json!(1e308));
        assert_eq!(parse_assignment("a.b=\"nan\"").unwrap().1, json!("nan"));
    }

    #[test]
    fn setting_through_a_value_that_is_not_a_table_names_it() {
        let mut d = doc(json!({"numerics": 1}));
        let err = set(&mut d, "numerics.integrator", json!("gear5")).unwrap_err();
        assert_eq!(err.field, "numerics");
        assert!(err.message.contains("a number"), "{}", err.message);
        set(&mut d, "box.width", json!(2.0)).unwrap();
        assert_eq!(get(&d, "box.width"), Some(&json!(2.0)));
        assert!(!has(&d, "box.height"));
    }

    #[test]
    fn defaults_fill_only_what_is_unset() {
        let mut d = doc(json!({"contact": {"mu": 0.3}}));
        merge_defaults(
            &mut d,
            &doc(json!({"contact": {"mu": 0.2, "k_n": 1e6}, "seed": 0})),
        );
        assert_eq!(
            d,
            doc(json!({"contact": {"mu": 0.3, "k_n": 1e6}, "seed": 0}))
        );
    }
}
