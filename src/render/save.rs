//! Writing rendered images as PNG: encoded in memory first and written through a temporary file renamed into
//! place, so a failure (another extension, a missing folder, a full disk) never leaves an empty or partial file
//! where the image should be.

use image::{ImageFormat, RgbaImage};
use std::path::Path;

/// Whether `path` is something other than a regular file that already exists (`/dev/null`, a pipe): written
/// directly, whatever its name.
fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// Refuses a name [`save`] would refuse, before anything is rendered.
pub fn check_name(path: &Path) -> Result<(), String> {
    if !is_special(path) && ImageFormat::from_path(path).ok() != Some(ImageFormat::Png) {
        return Err(format!(
            "{}: volcast writes PNG images; name the file *.png",
            path.display()
        ));
    }
    Ok(())
}

/// Writes `image` to `path` as PNG (the one format volcast writes; the name must end in `.png`). The error names the
/// file and the problem.
pub fn save(image: &RgbaImage, path: &Path) -> Result<(), String> {
    check_name(path)?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write_to(&mut bytes, ImageFormat::Png)
        .map_err(|e| format!("{}: cannot encode the image: {e}", path.display()))?;
    // A device or pipe is written directly: renaming over it would replace it.
    if is_special(path) {
        return std::fs::write(path, bytes.get_ref()).map_err(|e| format!("writing {}: {e}", path.display()));
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let written = std::fs::write(&tmp, bytes.get_ref()).and_then(|_| std::fs::rename(&tmp, path));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(format!("writing {}: {e}", path.display()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failures_leave_no_file_and_png_round_trips() {
        let dir = std::env::temp_dir().join(format!("volcast-image-out-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let img = RgbaImage::from_pixel(4, 3, image::Rgba([10, 200, 30, 255]));
        for name in ["x.notaformat", "x.jpg"] {
            let bad = dir.join(name);
            let e = save(&img, &bad).unwrap_err();
            assert!(e.contains(name) && e.contains("PNG"), "{e}");
            assert!(!bad.exists(), "{name} was created");
        }
        let missing = dir.join("no/such/dir/x.png");
        assert!(save(&img, &missing).unwrap_err().contains("x.png"));
        let png = dir.join("x.png");
        save(&img, &png).unwrap();
        assert_eq!(image::open(&png).unwrap().to_rgba8(), img);
        // A device is taken whatever its name and written directly, never renamed over (not exercised here: a
        // regression would replace the machine's /dev/null).
        assert!(is_special(Path::new("/dev/null")) && check_name(Path::new("/dev/null")).is_ok());
        let leftovers: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(leftovers.is_empty());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
