//! The pages a user reads, for the tests that hold them to what they say: the README and the
//! guide's (docs/guide/).

use std::path::{Path, PathBuf};

use super::workspace::workspace;

/// The README, then the guide's pages in order.
pub fn user_pages() -> Vec<PathBuf> {
    let mut pages = vec![workspace().join("README.md")];
    pages.extend(markdown_in(&workspace().join("docs/guide")));
    pages
}

/// The Markdown pages of `dir`, in order.
pub fn markdown_in(dir: &Path) -> Vec<PathBuf> {
    let mut pages: Vec<PathBuf> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "md")).collect();
    pages.sort();
    pages
}
