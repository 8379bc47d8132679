//! Writing rendered images as PNG, JPEG or TIFF, by the file's extension: encoded in memory first and written
//! through a temporary file renamed into place, so a failure (another extension, a missing folder, a full disk) never
//! leaves an empty or partial file where the image should be.

use image::RgbaImage;
use std::path::Path;

/// The formats volcast writes. PNG is lossless and keeps every value the tests compare; JPEG (quality 95) is for
/// slides and the web; TIFF (uncompressed RGBA) for journals that ask for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Png,
    Jpeg,
    Tiff,
}

const NAMES: &str = "*.png, *.jpg (or *.jpeg) or *.tif (or *.tiff)";

/// The format `path`'s extension names (any case); a device or pipe (`/dev/null`) is written as PNG.
fn kind_of(path: &Path) -> Option<Kind> {
    if is_special(path) {
        return Some(Kind::Png);
    }
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "png" => Some(Kind::Png),
        "jpg" | "jpeg" => Some(Kind::Jpeg),
        "tif" | "tiff" => Some(Kind::Tiff),
        _ => None,
    }
}

/// Whether `path` is something other than a regular file that already exists (`/dev/null`, a pipe): written
/// directly, whatever its name.
fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// Refuses a name [`save`] would refuse, before anything is rendered: an extension volcast does not write, or a
/// folder that does not exist.
pub fn check_name(path: &Path) -> Result<(), String> {
    if kind_of(path).is_none() {
        return Err(format!(
            "{}: volcast writes PNG, JPEG and TIFF images; name the file {NAMES}",
            path.display()
        ));
    }
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(folder) = folder.filter(|f| !f.is_dir()) {
        return Err(format!(
            "{}: the folder {} does not exist",
            path.display(),
            folder.display()
        ));
    }
    Ok(())
}

fn encode(image: &RgbaImage, kind: Kind) -> Result<Vec<u8>, String> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    let (w, h) = image.dimensions();
    match kind {
        Kind::Png => image
            .write_to(&mut bytes, image::ImageFormat::Png)
            .map_err(|e| e.to_string())?,
        Kind::Jpeg => {
            // JPEG has no alpha: the frames are opaque (rule 8 composites over the background).
            let rgb = image::DynamicImage::ImageRgba8(image.clone()).to_rgb8();
            let (w, h) = (
                u16::try_from(w).map_err(|_| "JPEG images are at most 65535 pixels wide")?,
                u16::try_from(h).map_err(|_| "JPEG images are at most 65535 pixels high")?,
            );
            jpeg_encoder::Encoder::new(&mut bytes, 95)
                .encode(rgb.as_raw(), w, h, jpeg_encoder::ColorType::Rgb)
                .map_err(|e| e.to_string())?
        }
        Kind::Tiff => tiff::encoder::TiffEncoder::new(&mut bytes)
            .and_then(|mut t| t.write_image::<tiff::encoder::colortype::RGBA8>(w, h, image.as_raw()))
            .map_err(|e| e.to_string())?,
    }
    Ok(bytes.into_inner())
}

/// Writes `image` to `path` as PNG, JPEG or TIFF, by its extension. The error names the file and the problem.
pub fn save(image: &RgbaImage, path: &Path) -> Result<(), String> {
    check_name(path)?;
    let kind = kind_of(path).unwrap_or(Kind::Png);
    let bytes = encode(image, kind).map_err(|e| format!("{}: cannot encode the image: {e}", path.display()))?;
    // A device or pipe is written directly: renaming over it would replace it.
    if is_special(path) {
        return std::fs::write(path, &bytes).map_err(|e| format!("writing {}: {e}", path.display()));
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let written = std::fs::write(&tmp, &bytes).and_then(|_| std::fs::rename(&tmp, path));
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
        for name in ["x.notaformat", "x.gif", "x"] {
            let bad = dir.join(name);
            let e = save(&img, &bad).unwrap_err();
            assert!(e.contains(name) && e.contains("PNG, JPEG and TIFF"), "{e}");
            assert!(!bad.exists(), "{name} was created");
        }
        let missing = dir.join("no/such/dir/x.png");
        let e = check_name(&missing).unwrap_err();
        assert!(e.contains("x.png") && e.contains("no/such/dir does not exist"), "{e}");
        let png = dir.join("x.png");
        save(&img, &png).unwrap();
        assert_eq!(image::open(&png).unwrap().to_rgba8(), img);
        // JPEG and TIFF by extension, in any case: the magic numbers say what was written.
        for (name, magic) in [
            ("x.JPG", &b"\xff\xd8\xff"[..]),
            ("x.jpeg", b"\xff\xd8\xff"),
            ("x.tif", b"II*\0"),
        ] {
            save(&img, &dir.join(name)).unwrap();
            assert!(std::fs::read(dir.join(name)).unwrap().starts_with(magic), "{name}");
        }
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
