//! `docs/architecture.md` stays true: its twin table lists every WGSL file once, with a Rust
//! twin that exists, and gives every traversal its role; every source file says what it is.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The rows of the twin table (between `<!-- twins -->` and `<!-- /twins -->`): the cells of
/// each, backticks removed.
fn twin_rows() -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(Path::new(ROOT).join("docs/architecture.md")).unwrap();
    let start = text
        .find("<!-- twins -->")
        .expect("the twin table's start marker");
    let end = text
        .find("<!-- /twins -->")
        .expect("the twin table's end marker");
    text[start..end]
        .lines()
        .filter(|l| l.starts_with("| `"))
        .map(|l| {
            l.trim_matches('|')
                .split('|')
                .map(|c| c.trim().replace('`', ""))
                .collect()
        })
        .collect()
}

fn files_with_extension(dir: &Path, extension: &str, found: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files_with_extension(&path, extension, found);
        } else if path.extension().is_some_and(|e| e == extension) {
            found.push(path);
        }
    }
}

fn relative(path: &Path) -> String {
    path.strip_prefix(ROOT)
        .unwrap()
        .to_string_lossy()
        .into_owned()
}

#[test]
fn the_twin_table_lists_every_wgsl_file_once_with_an_existing_twin() {
    let rows = twin_rows();
    let mut listed = BTreeSet::new();
    for row in &rows {
        assert_eq!(row.len(), 3, "a row of WGSL, twin and role: {row:?}");
        assert!(listed.insert(row[0].clone()), "{} listed twice", row[0]);
        assert!(
            Path::new(ROOT).join(&row[1]).is_file(),
            "{}: its twin {} does not exist",
            row[0],
            row[1]
        );
        assert!(!row[2].is_empty(), "{}: no role", row[0]);
    }
    let mut wgsl = Vec::new();
    files_with_extension(&Path::new(ROOT).join("wgsl"), "wgsl", &mut wgsl);
    let present: BTreeSet<String> = wgsl.iter().map(|p| relative(p)).collect();
    let missing: Vec<_> = present.difference(&listed).collect();
    let stale: Vec<_> = listed.difference(&present).collect();
    assert!(
        missing.is_empty(),
        "WGSL files not in the table: {missing:?}"
    );
    assert!(stale.is_empty(), "rows naming no WGSL file: {stale:?}");
}

#[test]
fn every_traversal_has_its_role() {
    const ROLES: [&str; 4] = ["renders", "reference", "fallback", "benchmark"];
    let rows = twin_rows();
    let traversals = rows
        .iter()
        .filter(|r| r[0].contains("traverse"))
        .collect::<Vec<_>>();
    assert_eq!(
        traversals.len(),
        2,
        "the GPU's two traversals: {traversals:?}"
    );
    for row in traversals {
        assert!(
            ROLES.iter().any(|role| row[2].contains(role)),
            "{}: `{}` names no role of {ROLES:?}",
            row[0],
            row[2]
        );
    }
    let text = std::fs::read_to_string(Path::new(ROOT).join("docs/architecture.md")).unwrap();
    for cpu in [
        "src/accel/wide.rs",
        "src/accel/wide/packet.rs",
        "src/accel/octet.rs",
    ] {
        let row = text
            .lines()
            .find(|l| l.starts_with(&format!("| `{cpu}`")))
            .unwrap_or_else(|| panic!("{cpu}: no row"));
        assert!(ROLES.iter().any(|role| row.contains(role)), "{row}");
        assert!(Path::new(ROOT).join(cpu).is_file(), "{cpu} does not exist");
    }
}

#[test]
fn every_source_file_says_what_it_is() {
    let mut sources = Vec::new();
    files_with_extension(&Path::new(ROOT).join("src"), "rs", &mut sources);
    for path in sources {
        let text = std::fs::read_to_string(&path).unwrap();
        let first = text
            .lines()
            .find(|l| !l.starts_with("#!["))
            .unwrap_or_default();
        assert!(
            first.starts_with("//! ") && first.len() > 20,
            "{}: its first line does not say what it is: {first:?}",
            relative(&path)
        );
    }
}

/// The command line's types live in the binary (`src/bin/chambre/`): the library names its
/// enums' values (`chambre::named`) and the binary builds clap's parsers from those names.
#[test]
fn the_library_defines_no_command_line_types() {
    let mut sources = Vec::new();
    files_with_extension(&Path::new(ROOT).join("src"), "rs", &mut sources);
    let bin = Path::new(ROOT).join("src/bin");
    let mut using_clap = Vec::new();
    for path in sources.iter().filter(|p| !p.starts_with(&bin)) {
        let text = std::fs::read_to_string(path).unwrap();
        for (n, line) in text.lines().enumerate() {
            if line.contains("clap::") || line.contains("use clap") {
                using_clap.push(format!("{}:{}", relative(path), n + 1));
            }
        }
    }
    assert!(
        using_clap.is_empty(),
        "the library uses clap: {using_clap:?}"
    );
}

/// `main.rs` only dispatches to the commands' files: under 400 lines. (Functions over 120
/// lines anywhere in `src/`: `tools/check_function_length.py`.)
#[test]
fn main_rs_only_dispatches_the_commands() {
    let main = Path::new(ROOT).join("src/bin/chambre/main.rs");
    let lines = std::fs::read_to_string(&main).unwrap().lines().count();
    assert!(lines < 400, "{}: {lines} lines", relative(&main));
}
