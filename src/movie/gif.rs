//! An animated, looping GIF written frame by frame: each RGBA8 frame is quantised (256 colours of its own, NeuQuant)
//! and streamed to a temporary file beside the target as it comes, so memory holds one frame whatever the length;
//! [`GifWriter::finish`] renames the file into place. A writer dropped unfinished (an error, a cancelled
//! recording) removes its temporary file: no half GIF is ever left under the target's name.

use super::MovieError;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

/// The fastest frame rate a GIF plays reliably: delays are whole hundredths of a second, and browsers slow any delay
/// under 2/100 s down to 1/10 s.
pub const MAX_FPS: f32 = 50.0;
/// The slowest frame rate accepted (10 s a frame).
pub const MIN_FPS: f32 = 0.1;
/// The default frame rate of `render --turntable` and `--keyframes`.
pub const DEFAULT_FPS: f32 = 25.0;

/// NeuQuant's sampling factor: 10 is the gif crate's recommended balance (1 is best and ~10x slower).
const QUANTISER_SPEED: i32 = 10;

/// Checks a frame rate; the message says what is allowed and why.
pub fn check_fps(fps: f32) -> Result<(), String> {
    if !(fps.is_finite() && (MIN_FPS..=MAX_FPS).contains(&fps)) {
        return Err(format!(
            "frame rate {fps} must be between {MIN_FPS} and {MAX_FPS} frames per second (a GIF's delays are whole \
             hundredths of a second, and viewers slow delays under 2/100 s down)"
        ));
    }
    Ok(())
}

/// The delay of frame `k` in hundredths of a second at `fps`: rounded so that the frames' start times stay within
/// half a hundredth of `k / fps` (30 fps alternates 3, 3 and 4).
pub fn frame_delay(k: u64, fps: f32) -> u16 {
    let at = |k: u64| (k as f64 * 100.0 / f64::from(fps)).round();
    (at(k + 1) - at(k)).clamp(1.0, f64::from(u16::MAX)) as u16
}

/// A GIF being written. See the module's docs.
pub struct GifWriter {
    path: PathBuf,
    tmp: PathBuf,
    encoder: Option<::gif::Encoder<BufWriter<File>>>,
    width: u16,
    height: u16,
    fps: f32,
    frames: u64,
    /// One frame's pixels, reused: quantisation rewrites them in place.
    scratch: Vec<u8>,
}

impl GifWriter {
    /// Starts `path` (created on [`GifWriter::finish`]) for frames of `width`×`height` at `fps`, looping forever.
    pub fn create(path: &Path, width: u32, height: u32, fps: f32) -> Result<GifWriter, MovieError> {
        check_fps(fps).map_err(MovieError::Usage)?;
        let side = |v: u32| u16::try_from(v).ok().filter(|&v| v > 0);
        let (Some(w), Some(h)) = (side(width), side(height)) else {
            return Err(MovieError::Usage(format!(
                "{}: a GIF's frames are 1 to 65535 pixels a side, not {width}x{height}",
                path.display()
            )));
        };
        static SERIAL: AtomicU32 = AtomicU32::new(0);
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let serial = SERIAL.fetch_add(1, Ordering::Relaxed);
        let tmp = path.with_file_name(format!(".{name}.{}.{serial}.tmp", std::process::id()));
        let write_error = |e: &dyn std::fmt::Display| MovieError::Write(format!("writing {}: {e}", path.display()));
        let file = File::create(&tmp).map_err(|e| write_error(&e))?;
        let started = ::gif::Encoder::new(BufWriter::new(file), w, h, &[]).and_then(|mut e| {
            e.set_repeat(::gif::Repeat::Infinite)?;
            Ok(e)
        });
        let encoder = match started {
            Ok(e) => e,
            Err(e) => {
                let _ = std::fs::remove_file(&tmp);
                return Err(write_error(&e));
            }
        };
        Ok(GifWriter {
            path: path.to_path_buf(),
            tmp,
            encoder: Some(encoder),
            width: w,
            height: h,
            fps,
            frames: 0,
            scratch: Vec::new(),
        })
    }

    /// Appends one frame: `rgba` holds `width`×`height` RGBA8 pixels, rows top first (what the renderer reads
    /// back). Alpha 0 is transparent, any other alpha opaque.
    pub fn push_rgba(&mut self, width: u32, height: u32, rgba: &[u8]) -> Result<(), MovieError> {
        self.push_rgba_for(width, height, rgba, frame_delay(self.frames, self.fps))
    }

    /// Appends one frame shown for `delay` hundredths of a second (the viewer's recording: each frame as long as
    /// it was on screen), instead of the writer's frame rate.
    pub fn push_rgba_for(&mut self, width: u32, height: u32, rgba: &[u8], delay: u16) -> Result<(), MovieError> {
        let (w, h) = (self.width, self.height);
        if (width, height) != (u32::from(w), u32::from(h)) || rgba.len() != usize::from(w) * usize::from(h) * 4 {
            return Err(MovieError::Usage(format!(
                "{}: every frame must be {w}x{h} like the first, not {width}x{height} ({} bytes)",
                self.path.display(),
                rgba.len()
            )));
        }
        self.scratch.clear();
        self.scratch.extend_from_slice(rgba);
        let mut frame = ::gif::Frame::from_rgba_speed(w, h, &mut self.scratch, QUANTISER_SPEED);
        frame.delay = delay;
        let encoder = self
            .encoder
            .as_mut()
            .ok_or_else(|| MovieError::Write(format!("{}: already finished", self.path.display())))?;
        encoder
            .write_frame(&frame)
            .map_err(|e| MovieError::Write(format!("writing {}: {e}", self.path.display())))?;
        self.frames += 1;
        Ok(())
    }

    /// Appends one rendered frame.
    pub fn push(&mut self, image: &image::RgbaImage) -> Result<(), MovieError> {
        self.push_rgba(image.width(), image.height(), image.as_raw())
    }

    /// Frames appended so far.
    pub fn frame_count(&self) -> u64 {
        self.frames
    }

    /// Ends the GIF and moves it into place; returns the number of frames. A GIF without frames is refused.
    pub fn finish(mut self) -> Result<u64, MovieError> {
        let write_error =
            |e: &dyn std::fmt::Display| MovieError::Write(format!("writing {}: {e}", self.path.display()));
        if self.frames == 0 {
            return Err(MovieError::Usage(format!(
                "{}: a GIF needs at least one frame",
                self.path.display()
            )));
        }
        let Some(encoder) = self.encoder.take() else {
            return Err(write_error(&"already finished"));
        };
        let written = encoder
            .into_inner()
            .map_err(|e| write_error(&e))
            .and_then(|mut out| out.flush().map_err(|e| write_error(&e)))
            .and_then(|()| std::fs::rename(&self.tmp, &self.path).map_err(|e| write_error(&e)));
        if written.is_err() {
            let _ = std::fs::remove_file(&self.tmp);
        }
        written.map(|()| self.frames)
    }
}

impl Drop for GifWriter {
    fn drop(&mut self) {
        // Unfinished: close the encoder first (it writes its trailer on drop), then remove the partial file.
        if let Some(encoder) = self.encoder.take() {
            drop(encoder);
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("volcast-gif-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn leftovers(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect()
    }

    #[test]
    fn delays_keep_the_frame_rate_on_average() {
        assert!((0..10).all(|k| frame_delay(k, 25.0) == 4));
        let thirty: Vec<u16> = (0..30).map(|k| frame_delay(k, 30.0)).collect();
        assert_eq!(thirty.iter().map(|&d| u32::from(d)).sum::<u32>(), 100, "{thirty:?}");
        assert!(thirty.iter().all(|&d| d == 3 || d == 4));
        assert_eq!(frame_delay(0, 0.1), 1000);
        for bad in [0.0, -1.0, 51.0, f32::NAN, f32::INFINITY] {
            assert!(check_fps(bad).unwrap_err().contains("frame rate"), "{bad}");
        }
        assert!(check_fps(50.0).is_ok() && check_fps(0.1).is_ok());
    }

    #[test]
    fn frames_stream_to_a_looping_gif() {
        let dir = scratch("ok");
        let path = dir.join("m.gif");
        let mut w = GifWriter::create(&path, 6, 4, 20.0).unwrap();
        assert!(!path.exists(), "the GIF appears only when finished");
        for k in 0..3u8 {
            let img = image::RgbaImage::from_pixel(6, 4, image::Rgba([k * 80, 255 - k * 80, 30, 255]));
            w.push(&img).unwrap();
        }
        let wrong = image::RgbaImage::new(5, 4);
        assert!(w.push(&wrong).unwrap_err().to_string().contains("6x4"));
        assert_eq!(w.finish().unwrap(), 3);
        assert_eq!(leftovers(&dir), vec!["m.gif".to_string()]);
        let mut opts = ::gif::DecodeOptions::new();
        opts.set_color_output(::gif::ColorOutput::RGBA);
        let mut d = opts.read_info(File::open(&path).unwrap()).unwrap();
        let mut frames = 0;
        while let Some(f) = d.read_next_frame().unwrap() {
            assert_eq!((f.width, f.height, f.delay), (6, 4, 5));
            assert_eq!(&f.buffer[..4], &[frames * 80, 255 - frames * 80, 30, 255]);
            frames += 1;
        }
        assert_eq!(frames, 3);
        assert_eq!(d.repeat(), ::gif::Repeat::Infinite);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn an_unfinished_or_empty_gif_leaves_nothing() {
        let dir = scratch("bad");
        let path = dir.join("m.gif");
        let mut w = GifWriter::create(&path, 2, 2, 25.0).unwrap();
        w.push(&image::RgbaImage::new(2, 2)).unwrap();
        drop(w);
        let w = GifWriter::create(&path, 2, 2, 25.0).unwrap();
        assert!(w.finish().unwrap_err().to_string().contains("at least one frame"));
        assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
        let missing = dir.join("no/such/m.gif");
        assert!(GifWriter::create(&missing, 2, 2, 25.0)
            .err()
            .unwrap()
            .to_string()
            .contains("m.gif"));
        assert!(GifWriter::create(&path, 0, 2, 25.0).is_err());
        assert!(GifWriter::create(&path, 2, 2, 0.0).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
