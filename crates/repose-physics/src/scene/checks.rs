//! Validation errors that name their field, and the checks that collect them.

use crate::doc::{shown_key, DocError};
use serde::{Deserialize, Serialize};
use std::fmt;

/// One rejected field and why.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FieldError {
    /// Dotted path of the field, e.g. `contact.mu`.
    pub field: String,
    pub message: String,
}

impl fmt::Display for FieldError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

/// Every problem found in a scene document.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, thiserror::Error)]
pub struct SceneError {
    pub errors: Vec<FieldError>,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let lines: Vec<String> = self.errors.iter().map(|e| e.to_string()).collect();
        write!(f, "invalid scene: {}", lines.join("; "))
    }
}

impl SceneError {
    pub fn single(field: impl Into<String>, message: impl Into<String>) -> Self {
        SceneError {
            errors: vec![FieldError {
                field: field.into(),
                message: message.into(),
            }],
        }
    }
}

impl From<DocError> for SceneError {
    fn from(e: DocError) -> Self {
        SceneError::single(e.field, e.message)
    }
}

/// A serde error at a path inside the document (`(document)` at the top).
pub(crate) fn path_error(path: String, message: String) -> SceneError {
    let field = if path.is_empty() || path == "." {
        "(document)".to_string()
    } else {
        path
    };
    SceneError::single(field, message)
}

/// Collects field errors during validation.
#[derive(Debug, Default)]
pub struct Checks(Vec<FieldError>);

impl Checks {
    pub fn fail(&mut self, field: &str, message: impl Into<String>) {
        self.0.push(FieldError {
            field: shown_key(field),
            message: message.into(),
        });
    }

    /// Adds every error of `e`.
    pub fn extend(&mut self, e: SceneError) {
        self.0.extend(e.errors);
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    pub fn finite(&mut self, field: &str, v: f64) -> bool {
        if !v.is_finite() {
            self.fail(field, format!("must be a finite number, got {v}"));
            return false;
        }
        true
    }

    pub fn positive(&mut self, field: &str, v: f64) {
        if self.finite(field, v) && v <= 0.0 {
            self.fail(field, format!("must be greater than 0, got {v}"));
        }
    }

    pub fn non_negative(&mut self, field: &str, v: f64) {
        if self.finite(field, v) && v < 0.0 {
            self.fail(field, format!("must be 0 or more, got {v}"));
        }
    }

    /// A fraction in (0, 1], or (0, 1) with `open_top`.
    pub fn fraction(&mut self, field: &str, v: f64, open_top: bool) {
        if self.finite(field, v) && (v <= 0.0 || v > 1.0 || (open_top && v == 1.0)) {
            let range = if open_top { "(0, 1)" } else { "(0, 1]" };
            self.fail(field, format!("must lie in {range}, got {v}"));
        }
    }

    /// `Ok` when nothing failed, else every failure.
    pub fn into_result(self) -> Result<(), SceneError> {
        if self.0.is_empty() {
            Ok(())
        } else {
            Err(SceneError { errors: self.0 })
        }
    }
}
