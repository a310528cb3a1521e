//! Exit statuses, in one place: 0 on success, 2 when the user's input is at
//! fault (the scene file, the arguments, an unreadable VDB or one the renderer
//! refuses, a scene the bake cannot honour, an output that is not ours to
//! replace), 1 for anything else, and [`CANCELLED`] when a host program
//! asked the bake to stop (`aurora bake --cancel-file`).
//!
//! One rule decides between 2 and 1: every library error type answers
//! `is_input()`, and [`is_input`] asks the error that reached `main`. The
//! binary's own refusals are [`InputError`]s.

/// The process succeeded.
pub const SUCCESS: i32 = 0;
/// Something other than the input failed (an I/O error writing, say).
pub const FAILURE: i32 = 1;
/// The user's input is at fault.
pub const BAD_INPUT: i32 = 2;
/// The bake was asked to stop (`--cancel-file`): 128 + SIGINT's number, the
/// status a shell reports for a run ended by Ctrl-C, on every platform.
pub const CANCELLED: i32 = 130;

/// An error that is the user's input: exit status 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct InputError(pub String);

impl InputError {
    /// Always the user's input (the same question as the library's errors).
    pub fn is_input(&self) -> bool {
        true
    }
}

/// A library error reported by its message alone (no repeated causes), as
/// its own `is_input()` (`input`) classed it: an [`InputError`] (exit status
/// 2), or else a failure (exit status 1).
pub fn by_message(message: String, input: bool) -> anyhow::Error {
    if input {
        InputError(message).into()
    } else {
        anyhow::anyhow!(message)
    }
}

/// The exit status of a command's result; an error is printed on stderr
/// (with its causes) first, as a line of text or, with `json`, as the
/// object `{"error", "status", "seconds"}` (`--progress json`).
pub fn code(result: anyhow::Result<()>, json: bool) -> i32 {
    match result {
        Ok(()) => SUCCESS,
        Err(e) => {
            let status = if is_input(&e) { BAD_INPUT } else { FAILURE };
            if json {
                aurora::util::progress::JsonProgress::new(std::io::stderr()).error(&format!("{e:#}"), status);
            } else {
                eprintln!("aurora: error: {e:#}");
            }
            status
        }
    }
}

/// Whether the error that reached `main` is the user's input: the answer of
/// its own type's `is_input()` (a context added on the way keeps the type).
/// Errors of any other type are not.
pub fn is_input(e: &anyhow::Error) -> bool {
    macro_rules! ask {
        ($($t:ty),* $(,)?) => {
            $(if let Some(x) = e.downcast_ref::<$t>() {
                return x.is_input();
            })*
        };
    }
    ask!(
        InputError,
        aurora::scene::SceneError,
        aurora::physics::data_files::DataError,
        aurora::pipeline::bake::BakeError,
        aurora::pipeline::beams::BeamError,
        aurora::util::atomic_write::AtomicError,
        aurora::io::bake_folder::OutputError,
        aurora::farm::sequence_folder::SequenceError,
        aurora::farm::cost_plan::PlanError,
        aurora::pipeline::footprint::FootprintError,
        aurora::render::RenderError,
        aurora::app::preview::PreviewError,
        aurora::app::keogram::KeogramError,
        aurora::app::scene_input::SceneInputError,
        aurora::app::render_image::RenderImageError,
        aurora::app::bake_sequence::SequenceBakeError,
        aurora::app::bench::harness::SweepError,
        aurora::app::bench::report::ReportError,
    );
    false
}
