//! Contact models: the material of a scene and the compiled engines it runs on.
//!
//! A model owns the sections of a scene that describe grains and contacts
//! (Lee & Herrmann's `[grains]`, `[contact]` and `[wall_contact]`), their
//! defaults, the time scale of a contact, and the choice of compiled engine:
//! which integrator and which contact-law components a scene's options ask
//! for. That choice is one flat list per model (`select!`): each option is
//! one line naming the types it can be, and every combination is compiled,
//! so a scene pays only for the physics it switches on.
//!
//! Adding a model is its own module plus one line in the registry's
//! `MODELS` (and one in the [`Models`] impl of each dimension it has).

pub mod elekes_parteli;
pub mod lee_herrmann;

use crate::doc::Doc;
use crate::scene::{Checks, Scene, SceneError, SectionDecl};
use repose_engine::contact::{ContactLaw, Frictionless, NoRolling, Pairwise};
use repose_engine::dim::{Dim, Space};
use repose_engine::integrate::Integrator;
use repose_engine::simulation::Units;
use std::collections::BTreeMap;

/// A contact-law component built from a model's parameters `P` for one
/// kind of contact (grain–grain or grain–wall). Both models build their
/// laws this way; an option that is off builds from nothing.
pub trait Build<P> {
    fn build(p: &P) -> Self;
}

impl<P> Build<P> for Frictionless {
    fn build(_: &P) -> Self {
        Frictionless
    }
}

impl<P> Build<P> for NoRolling {
    fn build(_: &P) -> Self {
        NoRolling
    }
}

/// The contact law of the components `N`, `T`, `R`, `C` (rotating if
/// `ROT`), each built from the parameters `p`.
pub fn assemble<P, N, T, R, C, const ROT: bool>(p: &P) -> Pairwise<N, T, R, C, ROT>
where
    N: Build<P>,
    T: Build<P>,
    R: Build<P>,
    C: Build<P>,
{
    Pairwise {
        normal: N::build(p),
        tangential: T::build(p),
        rolling: R::build(p),
        cohesion: C::build(p),
    }
}

/// A contact model as the scene and the registry see it.
pub trait Model: Sync {
    /// The name scenes use (`model = "…"`).
    fn name(&self) -> &'static str;
    /// One line on what it models.
    fn about(&self) -> &'static str;
    /// The dimensions it has a form for.
    fn dimensions(&self) -> &'static [usize];
    /// The units its sections and results are in.
    fn units(&self) -> Units;
    /// The sections it owns.
    fn sections(&self) -> Vec<SectionDecl>;
    /// Core values it sets where a document is silent (gravity, numerics),
    /// given the document as written.
    fn defaults(&self, dimension: usize, doc: &Doc) -> Doc;
    /// Checks across its sections and the core.
    fn check(&self, scene: &Scene, c: &mut Checks);
    /// Writes out the values derived from others.
    fn resolve(&self, scene: &mut Scene);
    /// Duration of the stiffest contact at the reference speed.
    fn contact_time(&self, scene: &Scene) -> f64;
    /// The time in which the attraction of two touching grains alone would
    /// bring them to the speed `√(g d)`, s; none where grains do not
    /// attract (or nothing sets the speed).
    fn attraction_time(&self, _scene: &Scene) -> Option<f64> {
        None
    }
    /// Density of the grains (their mass is that of a sphere).
    fn density(&self, scene: &Scene) -> f64;
    /// The physics options a run used, by name, for its report.
    fn options(&self, scene: &Scene) -> BTreeMap<String, String>;
    /// Every how many steps (at the next neighbour-list build) the engine
    /// renumbers the grains in space (0: never, which keeps the results of
    /// earlier versions).
    fn sort_every(&self) -> u64 {
        0
    }
}

/// The contact laws of a run: one between grains, one between a grain and a wall.
#[derive(Debug, Clone, Copy)]
pub struct Laws<L> {
    pub pair: L,
    pub wall: L,
}

/// Something to do with the compiled engine a scene asks for, whatever its types.
pub trait EngineJob<const D: usize>
where
    Dim<D>: Space<D>,
{
    type Output;
    fn run<L: ContactLaw<D>, I: Integrator<D>>(self, laws: Laws<L>) -> Self::Output;
}

/// Widest Verlet skin, in diameters of the largest grain: a wider one lists
/// pairs far out of reach, up to every pair of the scene.
pub const MAX_SKIN: f64 = 10.0;

/// Refuses a skin wider than [`MAX_SKIN`] diameters of the largest grain,
/// of the model's grains (`drawn`, their largest diameter) or the listed ones.
pub fn check_skin(scene: &Scene, drawn: f64, c: &mut Checks) {
    let listed = scene.particles.iter().map(|p| 2.0 * p.radius);
    let largest_diameter = listed.fold(drawn, f64::max);
    let skin = scene.numerics.skin;
    if skin > MAX_SKIN * largest_diameter {
        c.fail(
            "numerics.skin",
            format!(
                "{skin} is wider than {MAX_SKIN} diameters of the largest grain ({largest_diameter}): \
                 the list would hold pairs far out of reach"
            ),
        );
    }
}

/// The models that have a form in dimension `D`.
pub trait Models<const D: usize>
where
    Dim<D>: Space<D>,
{
    /// Runs `job` on the engine the scene's model and options select.
    fn with_engine<J: EngineJob<D>>(scene: &Scene, job: J) -> Result<J::Output, SceneError>;
}

impl Models<2> for Dim<2> {
    fn with_engine<J: EngineJob<2>>(scene: &Scene, job: J) -> Result<J::Output, SceneError> {
        match scene.model.as_str() {
            lee_herrmann::NAME => lee_herrmann::with_engine(scene, job),
            other => Err(no_form(other, 2)),
        }
    }
}

impl Models<3> for Dim<3> {
    fn with_engine<J: EngineJob<3>>(scene: &Scene, job: J) -> Result<J::Output, SceneError> {
        match scene.model.as_str() {
            lee_herrmann::NAME => lee_herrmann::with_engine(scene, job),
            elekes_parteli::NAME => elekes_parteli::with_engine(scene, job),
            other => Err(no_form(other, 3)),
        }
    }
}

fn no_form(model: &str, dimension: usize) -> SceneError {
    SceneError::single("model", format!("model {model} has no {dimension}D form"))
}

/// Runs `job` on the engine a (resolved) scene asks for.
pub fn with_engine<const D: usize, J: EngineJob<D>>(
    scene: &Scene,
    job: J,
) -> Result<J::Output, SceneError>
where
    Dim<D>: Space<D> + Models<D>,
{
    <Dim<D> as Models<D>>::with_engine(scene, job)
}

/// Chooses one type per option from run-time values and evaluates the body
/// with those types in scope: every combination is compiled, and the list
/// of options stays flat however many there are.
///
/// ```ignore
/// select! {
///     I = scheme => { Scheme::Gear5 => Gear5, Scheme::Verlet => VelocityVerlet };
///     N = floor => { true => HertzDamped<true>, false => HertzDamped<false> };
///     => job.run::<Pairwise<N, Frictionless>, I>(laws)
/// }
/// ```
macro_rules! select {
    (=> $body:expr) => {
        $body
    };
    (@each $name:ident, $e:expr, { $($pat:pat => $ty:ty),+ $(,)? }, $rest:tt) => {
        match $e {
            $($pat => {
                type $name = $ty;
                $crate::models::select!(@unwrap $rest)
            })+
        }
    };
    (@unwrap [$($rest:tt)*]) => {
        $crate::models::select!($($rest)*)
    };
    ($name:ident = $e:expr => $arms:tt; $($rest:tt)*) => {
        $crate::models::select!(@each $name, $e, $arms, [$($rest)*])
    };
}
pub(crate) use select;
