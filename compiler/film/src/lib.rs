//! Film grammar's checks on a directed flight (`film::` codes): what a script editor checks
//! in a cut before anyone flies — the line of action between two actors
//! (`film::crosses_line`), cuts too alike to read as cuts (`film::jump_cut`), an actor's
//! walk reversing across a cut (`film::screen_direction`) — and framed actors that leave the
//! frame (`film::out_of_frame`).
//!
//! They watch the director's samples ([`dronecine_compiler::director::Watch`]): the same
//! checks on the compiled reference against the script's blocking ([`compile()`]) and, on set,
//! on the reference the director flies against the live actors ([`watch`]), each shot's
//! findings told when the shot ends, as the director's own are. A tick allocates nothing.

mod code;
mod frame;
mod seen;

pub use code::FilmCode;

use dronecine_compiler::compile::{self, Compiled, Options};
use dronecine_compiler::director::Watch;
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_diag::Diagnostic;
use dronecine_grammar::script::{Scene, Script};
use dronecine_profile::Profile;

/// The film checks of `script` flown with `profile`, for a director to be watched by.
pub fn watch(script: &Script, scene: &Scene, profile: &Profile) -> Box<dyn Watch> {
    let lens = dronecine_compiler::director::scene_lens(scene, profile);
    Box::new(seen::Film::new(script, scene, lens, profile.camera.gimbal))
}

/// [`compile::compile`] with the film checks' findings among its diagnostics.
pub fn compile<E>(
    script: &Script,
    profile: &Profile,
    opts: &Options,
    sink: impl FnMut(&Sample, &[ActorPose]) -> Result<(), E>,
) -> Result<Compiled, E> {
    let watch = script
        .scene
        .as_ref()
        .map(|scene| watch(script, scene, profile));
    compile::compile_watched(script, profile, opts, watch, sink)
}

/// The `film::` findings of a compilation only.
pub fn findings(compiled: &Compiled) -> impl Iterator<Item = &Diagnostic> {
    compiled
        .diagnostics
        .iter()
        .filter(|d| d.code.namespace() == "film")
}
