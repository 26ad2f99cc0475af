//! The registry: every protocol and every contact model by name, the one
//! place that knows them all. The store, the API, the exports and the page
//! learn protocols, their metrics and the models from here; a scene is
//! built and validated here against the sections its protocol and model
//! declare (`build`). Registering a protocol or a model is its module plus
//! one line below.

mod build;

use crate::models::{self, Model};
use crate::protocols::{self, Metric, Protocol};

/// Every protocol, by name: registering one is its line here.
pub static PROTOCOLS: &[&dyn Protocol] = &[
    &protocols::fill_release::FillRelease,
    &protocols::tilt::Tilt,
    &protocols::flux::Flux,
    &protocols::free_run::FreeRun,
    &protocols::heap::Heap,
    &protocols::packing::Packing,
];

/// Every contact model, by name: registering one is its line here.
pub static MODELS: &[&dyn Model] = &[
    &models::lee_herrmann::LeeHerrmann,
    &models::elekes_parteli::ElekesParteli,
];

/// All registered protocols.
pub fn protocols() -> &'static [&'static dyn Protocol] {
    PROTOCOLS
}

/// The protocol of this name.
pub fn find_protocol(name: &str) -> Option<&'static dyn Protocol> {
    PROTOCOLS.iter().copied().find(|p| p.name() == name)
}

/// The registered protocols' names.
pub fn protocol_names() -> Vec<&'static str> {
    PROTOCOLS.iter().map(|p| p.name()).collect()
}

/// The metric of this name in any protocol.
pub fn find_metric(name: &str) -> Option<&'static Metric> {
    PROTOCOLS
        .iter()
        .flat_map(|p| p.metrics())
        .find(|m| m.name == name)
}

/// The model of this name.
pub fn find_model(name: &str) -> Option<&'static dyn Model> {
    MODELS.iter().copied().find(|m| m.name() == name)
}

/// The registered models' names.
pub fn model_names() -> Vec<&'static str> {
    MODELS.iter().map(|m| m.name()).collect()
}
