//! Placeholder: the parser is being written.
use crate::{ast::SceneFile, diag::Diagnostic};

pub fn parse(_source: &str) -> Result<SceneFile, Vec<Diagnostic>> {
    Ok(SceneFile::default())
}
