//! The viewer's record button (F9, or Record in the panel's View section): the 3D view's frames, as shown, into a
//! looping GIF in the working directory (`volcast-<time>.gif`). Each frame lasts as long as it was on screen, so
//! the GIF plays at the speed the view moved. While recording, every frame is rendered at full detail (no reduced
//! frames while the view moves), read back and encoded before the next: the view runs slower.

use crate::movie::gif::GifWriter;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A recording in progress. The GIF is created with the first frame (its size is the view's then); a frame is
/// written when the next arrives, once its time on screen is known.
pub struct Recorder {
    path: PathBuf,
    writer: Option<GifWriter>,
    size: (u32, u32),
    held: Option<(Vec<u8>, Instant)>,
}

/// A frame's delay in hundredths of a second: its time on screen, at least 2 (GIF viewers slow shorter delays).
pub fn delay_cs(shown_s: f64) -> u16 {
    (shown_s * 100.0).round().clamp(2.0, f64::from(u16::MAX)) as u16
}

impl Recorder {
    pub fn new(path: PathBuf) -> Recorder {
        Recorder {
            path,
            writer: None,
            size: (0, 0),
            held: None,
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Takes the frame shown at `at`: `rgba` holds `width`×`height` pixels. A view that changes size ends the
    /// recording with an error (the GIF keeps one size); the caller then stops it.
    pub fn push(&mut self, width: u32, height: u32, rgba: Vec<u8>, at: Instant) -> Result<(), String> {
        if self.writer.is_none() {
            let w = GifWriter::create(&self.path, width, height, 10.0).map_err(|e| e.to_string())?;
            (self.writer, self.size) = (Some(w), (width, height));
        }
        if (width, height) != self.size {
            return Err(format!(
                "{}: the view changed size from {}x{} to {width}x{height}; the recording stops there",
                self.path.display(),
                self.size.0,
                self.size.1
            ));
        }
        self.write_held(at)?;
        self.held = Some((rgba, at));
        Ok(())
    }

    fn write_held(&mut self, now: Instant) -> Result<(), String> {
        if let (Some((rgba, shown)), Some(w)) = (self.held.take(), self.writer.as_mut()) {
            let delay = delay_cs(now.duration_since(shown).as_secs_f64());
            w.push_rgba_for(self.size.0, self.size.1, &rgba, delay)
                .map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    /// Writes the last frame (a tenth of a second) and the GIF; returns its frame count. Nothing recorded: an
    /// error, and no file.
    pub fn finish(mut self, now: Instant) -> Result<u64, String> {
        let held = self.held.as_ref().map(|(_, t)| *t);
        let end = held.map_or(now, |t| now.min(t + std::time::Duration::from_millis(100)).max(t));
        self.write_held(end)?;
        match self.writer.take() {
            Some(w) => w.finish().map_err(|e| e.to_string()),
            None => Err(format!("{}: no frame was recorded", self.path.display())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn frames_last_as_long_as_they_were_shown() {
        let dir = std::env::temp_dir().join(format!("volcast-record-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("r.gif");
        let mut r = Recorder::new(path.clone());
        let t0 = Instant::now();
        let frame = |v: u8| vec![v; 4 * 4 * 4];
        r.push(4, 4, frame(10), t0).unwrap();
        r.push(4, 4, frame(200), t0 + Duration::from_millis(250)).unwrap();
        r.push(4, 4, frame(90), t0 + Duration::from_millis(260)).unwrap();
        // Another size is refused, naming the file.
        let e = r.push(8, 4, vec![0; 8 * 4 * 4], t0).unwrap_err();
        assert!(e.contains("r.gif") && e.contains("changed size"), "{e}");
        assert_eq!(r.finish(t0 + Duration::from_secs(5)).unwrap(), 3);
        let mut decoder = gif::DecodeOptions::new();
        decoder.set_color_output(gif::ColorOutput::RGBA);
        let mut d = decoder.read_info(std::fs::File::open(&path).unwrap()).unwrap();
        let mut delays = Vec::new();
        while let Some(f) = d.read_next_frame().unwrap() {
            delays.push(f.delay);
        }
        // 0.25 s, then 0.01 s (at least 2/100), then the last frame's tenth of a second.
        assert_eq!(delays, vec![25, 2, 10]);
        // Nothing recorded: no file.
        let empty = dir.join("empty.gif");
        assert!(Recorder::new(empty.clone()).finish(t0).is_err());
        assert!(!empty.exists());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
