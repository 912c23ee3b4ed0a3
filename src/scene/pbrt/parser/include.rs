//! `Include` and `Import`: reading a named file into tokens, with the checks every file gets
//! (readable, UTF-8, not open already, not nested too deep). `Include` splices the tokens
//! into the stream (pbrt-v3 reads on from the included file's end into the includer, so a
//! parameter list may continue after the `Include` line); `Import` (pbrt-v4) reads the file
//! on its own and keeps the graphics state. Owns files and their order; must not interpret
//! directives.

use super::super::PbrtError;
use super::super::Place;
use super::super::args::Args;
use super::super::cursor::Cursor;
use super::super::lexer::{Token, tokens};
use super::Parser;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Deeper `Include` nesting than this is taken for a cycle nobody meant.
const MAX_INCLUDE_DEPTH: usize = 32;

impl Parser<'_> {
    /// Resolves a path named in the files: relative to the main file's folder, as pbrt does.
    pub(in super::super) fn resolve(folder: &Path, name: &str) -> PathBuf {
        let p = Path::new(name);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            folder.join(p)
        }
    }

    /// Reads `path`'s tokens, refusing a file already open in `open` (or in an `Import` being
    /// read) or one nested too deep. Returns the tokens and the file's identity.
    pub(super) fn open_file(
        &mut self,
        path: &Path,
        included_at: Option<&Place>,
        open: Option<&Cursor>,
    ) -> Result<(Vec<Token>, PathBuf), PbrtError> {
        let refuse = |message: String| match included_at {
            Some(at) => at.error("Include", message),
            None => PbrtError {
                file: path.to_path_buf(),
                line: None,
                column: None,
                field: "scene".into(),
                message,
            },
        };
        let depth = self.importing.len() + open.map_or(0, Cursor::depth);
        if depth >= MAX_INCLUDE_DEPTH {
            return Err(refuse(format!(
                "includes nest deeper than {MAX_INCLUDE_DEPTH} files (a cycle?)"
            )));
        }
        let identity = self.files.identity(path);
        if self.importing.contains(&identity) || open.is_some_and(|c| c.is_open(&identity)) {
            return Err(refuse(format!("`{}` includes itself", path.display())));
        }
        let bytes = (self.files.read(path))
            .map_err(|err| refuse(format!("cannot read `{}`: {err}", path.display())))?;
        let text = String::from_utf8(bytes)
            .map_err(|_| refuse(format!("`{}` is not UTF-8 text", path.display())))?;
        self.out.files.push(path.to_path_buf());
        let file: Arc<Path> = Arc::from(path);
        let tokens = tokens(&text, &file).map_err(|e| PbrtError {
            file: path.to_path_buf(),
            line: Some(e.line),
            column: Some(e.column),
            field: "syntax".into(),
            message: e.message,
        })?;
        Ok((tokens, identity))
    }

    /// `Include "f"` (splices f's tokens in) or `Import "f"` (reads f on its own, then
    /// restores the graphics state: it shares named things only).
    pub(super) fn include(&mut self, directive: &str, args: &mut Args) -> Result<(), PbrtError> {
        let place = args.place.clone();
        let name = args.string("file name")?;
        let path = Self::resolve(&self.search_folder, &name);
        let (tokens, identity) = self.open_file(&path, Some(&place), Some(args.tokens))?;
        if directive == "Include" {
            args.tokens.push(tokens, identity);
            return Ok(());
        }
        self.v4(&place, "Import");
        let saved = self.state.clone();
        let outer: Vec<PathBuf> = args.tokens.open_files().cloned().collect();
        let before = self.importing.len();
        self.importing.extend(outer);
        let result = self.run(&mut Cursor::new(tokens, identity));
        self.importing.truncate(before);
        self.state = saved;
        result
    }
}
