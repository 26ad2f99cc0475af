//! Quantities a paper's figures plot that are computed from the axis
//! values of a point (the Bond number from d and g, say), and reading a
//! point's value along an axis or such a quantity.

use serde_json::{Map, Value};

/// A quantity computed from the axis values of a point.
pub struct Quantity {
    /// The name figures use in place of an axis, e.g. `ep21.bond`.
    pub name: &'static str,
    /// Its symbol in labels, e.g. `Bo`.
    pub symbol: &'static str,
    pub f: fn(&Map<String, Value>) -> Option<f64>,
}

/// The value of `x` at a point: the axis of that name, or the quantity of
/// that name among `quantities` (a paper's), computed from the point's axes.
pub fn x_value(point: &Map<String, Value>, x: &str, quantities: &[Quantity]) -> Option<f64> {
    if let Some(v) = point.get(x) {
        return v.as_f64();
    }
    quantities
        .iter()
        .find(|q| q.name == x)
        .and_then(|q| (q.f)(point))
}

/// How labels name an axis or quantity: its symbol, or the axis itself.
pub fn symbol<'a>(x: &'a str, quantities: &[Quantity]) -> &'a str {
    quantities
        .iter()
        .find(|q| q.name == x)
        .map_or(x, |q| q.symbol)
}

/// The value that names a point's series along `axis` (an axis value, or
/// a computed quantity as a number; null when neither is known).
pub fn series_value(point: &Map<String, Value>, axis: &str, quantities: &[Quantity]) -> Value {
    match point.get(axis) {
        Some(v) => v.clone(),
        None => x_value(point, axis, quantities).map_or(Value::Null, Value::from),
    }
}
