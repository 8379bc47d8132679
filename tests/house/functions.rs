//! No function in src/ is longer than a reader takes in at once (ARCHITECTURE.md): 120 lines at most, counted
//! from its `fn` line to its closing brace at the same indentation, as rustfmt lays the code out.

use std::path::{Path, PathBuf};

const LONGEST: usize = 120;

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// (name, first line, length) of every function whose body is a block closed at its own indentation.
fn functions(text: &str) -> Vec<(String, usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let code = line.trim_start();
        let indent = line.len() - code.len();
        let signature = code
            .trim_start_matches("pub ")
            .trim_start_matches("pub(crate) ")
            .trim_start_matches("pub(super) ")
            .trim_start_matches("const ")
            .trim_start_matches("unsafe ");
        let Some(rest) = signature.strip_prefix("fn ") else {
            continue;
        };
        if line.trim_end().ends_with(';') {
            continue;
        }
        let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        let close = " ".repeat(indent) + "}";
        if let Some(end) = lines[i..]
            .iter()
            .position(|l| l.starts_with(&close) && !l[indent..].starts_with("} "))
        {
            out.push((name, i + 1, end + 1));
        }
    }
    out
}

#[test]
fn functions_stay_readable_at_once() {
    let mut files = Vec::new();
    rust_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), &mut files);
    let mut seen = 0;
    let mut long = Vec::new();
    for file in files {
        for (name, line, length) in functions(&std::fs::read_to_string(&file).unwrap()) {
            seen += 1;
            if length > LONGEST {
                long.push(format!("{}:{line} {name} has {length} lines", file.display()));
            }
        }
    }
    assert!(seen > 1000, "the scan found too few functions ({seen})");
    assert!(long.is_empty(), "split these into named steps:\n{}", long.join("\n"));
}

#[test]
fn the_scan_measures_a_function() {
    let text = "fn short() {\n    1\n}\n\nimpl A {\n    pub fn method(&self) {\n        if x {\n        }\n    }\n}\n";
    let found = functions(text);
    assert_eq!(found, vec![("short".into(), 1, 3), ("method".into(), 6, 4)]);
}
