//! Finding and reading scripts named on the command line, and preparing the files the
//! commands write.

use std::path::{Path, PathBuf};

/// Expand directories into the `.psl` files under them (sorted); keep files as given.
pub fn expand(inputs: &[PathBuf]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for input in inputs {
        if input.is_dir() {
            let mut found = Vec::new();
            walk(input, &mut found);
            found.sort();
            out.extend(found);
        } else {
            out.push(input.clone());
        }
    }
    out
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            walk(&path, out);
        } else if path.extension().is_some_and(|e| e == "psl") {
            out.push(path);
        }
    }
}

/// The directory a script's relative file names are resolved against.
pub fn base_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Write a file through a temporary sibling and a rename, so that a crash never leaves a
/// half-written script.
pub fn write_atomic(path: &Path, text: &str) -> std::io::Result<()> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.dronecine-tmp"));
    std::fs::write(&tmp, text)?;
    if let Ok(meta) = std::fs::metadata(path) {
        let _ = std::fs::set_permissions(&tmp, meta.permissions());
    }
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

/// Makes ready for `path` to be written by the option `flag` (`-o`, `--csv`, `--log`): its
/// folder is created if missing, and a path that names a folder is refused. Called before the
/// work that the file will hold, so that a calibration flight or a compilation is never done
/// for an output that cannot be written.
pub fn prepare_output(path: &Path, flag: &str) -> Result<(), String> {
    if path.is_dir() {
        return Err(format!(
            "{flag} `{}` is a folder: name a file in it, such as `{}`",
            path.display(),
            path.join("out").display()
        ));
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| {
            format!(
                "cannot create the folder `{}` for {flag} `{}`: {e}",
                dir.display(),
                path.display()
            )
        })?;
    }
    Ok(())
}

/// Makes the output folder `dir` (for `flag`), or says why it cannot be: a file stands there
/// or in its way, or the folder cannot be written. Checked before any output is written, so
/// that a command that cannot write all its outputs writes none.
pub fn prepare_folder(dir: &Path, flag: &str) -> Result<(), String> {
    let cannot =
        |e: std::io::Error| format!("{flag} `{}`: cannot make the folder: {e}", dir.display());
    if dir.exists() && !dir.is_dir() {
        return Err(format!(
            "{flag} `{}` is a file, not a folder",
            dir.display()
        ));
    }
    std::fs::create_dir_all(dir).map_err(cannot)?;
    // Written to before anything else is: a folder it cannot write to fails now.
    let probe = dir.join(format!(".dronecine-probe-{}", std::process::id()));
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .and_then(|_| std::fs::remove_file(&probe))
        .map_err(|e| {
            format!(
                "{flag} `{}`: cannot write in the folder: {e}",
                dir.display()
            )
        })
}

#[cfg(test)]
mod tests {
    use super::{prepare_folder, prepare_output};

    #[test]
    fn an_output_folder_is_made_or_refused_before_anything_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let deep = dir.path().join("a/b");
        prepare_folder(&deep, "--preview").unwrap();
        assert!(deep.is_dir());
        assert_eq!(
            std::fs::read_dir(&deep).unwrap().count(),
            0,
            "the probe is gone"
        );
        let file = dir.path().join("afile");
        std::fs::write(&file, "x").unwrap();
        let e = prepare_folder(&file, "--preview").unwrap_err();
        assert!(e.contains("is a file"), "{e}");
        let e = prepare_folder(&file.join("prev"), "--preview").unwrap_err();
        assert!(e.contains("cannot make the folder"), "{e}");
    }

    #[test]
    fn an_output_gets_its_folder_and_a_folder_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let deep = dir.path().join("a/b/out.mcap");
        prepare_output(&deep, "-o").unwrap();
        assert!(dir.path().join("a/b").is_dir());
        assert!(!deep.exists(), "only the folder is made");
        let e = prepare_output(dir.path(), "-o").unwrap_err();
        assert!(e.contains("is a folder"), "{e}");
        // A folder where a parent should be is a clear error, not a panic.
        std::fs::write(dir.path().join("file"), "x").unwrap();
        let e = prepare_output(&dir.path().join("file/out.mcap"), "--csv").unwrap_err();
        assert!(e.starts_with("cannot create the folder"), "{e}");
        assert!(e.contains("--csv"), "{e}");
    }
}
