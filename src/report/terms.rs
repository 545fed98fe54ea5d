//! `recommendation.<engine>.txt`: an engine's setting in the engine's own configuration
//! language (the language and template are the engine's, [`crate::presets::Terms`]).

use crate::commands::terms::EngineSetting;

/// The file's text.
pub fn text(s: &EngineSetting) -> String {
    let engine = s.preset.engine();
    let values = engine.terms_values(&s.knobs, &s.dims, s.near, s.far);
    crate::presets::render(engine, &values, &s.comments)
}

/// The file: (name, bytes).
pub(crate) fn file(s: &EngineSetting) -> (String, Vec<u8>) {
    (s.file_name(), text(s).into_bytes())
}
