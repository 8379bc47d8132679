//! The names the viewer gives what it writes into the working directory (F12 screenshots, F9 recordings, exported
//! figures): `volcast-2026-11-26_12-03-45.png`, the local date and time a person reads at a glance, made unique
//! with `-2`, `-3`… when two land in the same second.

use std::path::{Path, PathBuf};

/// A local date and time: year, month, day, hour, minute, second.
pub type DateTime = [i32; 6];

/// `volcast-<local date and time>.<ext>` (or `-2`, `-3`… before the extension), the first name `taken` refuses.
/// The path is absolute, so "saved …" says where the file is, whatever the working folder.
pub(super) fn capture_path(ext: &str, taken: impl Fn(&Path) -> bool) -> PathBuf {
    let path = unique_path(&stem(local_now()), ext, taken);
    std::path::absolute(&path).unwrap_or(path)
}

/// `volcast-YYYY-MM-DD_HH-MM-SS`: sorts by time, and has no `:` (which some file systems refuse).
pub fn stem([y, mo, d, h, mi, s]: DateTime) -> String {
    format!("volcast-{y:04}-{mo:02}-{d:02}_{h:02}-{mi:02}-{s:02}")
}

/// `stem.ext`, else `stem-2.ext`, `stem-3.ext`…: the first one `taken` refuses.
pub fn unique_path(stem: &str, ext: &str, taken: impl Fn(&Path) -> bool) -> PathBuf {
    let first = PathBuf::from(format!("{stem}.{ext}"));
    if !taken(&first) {
        return first;
    }
    (2u32..)
        .map(|n| PathBuf::from(format!("{stem}-{n}.{ext}")))
        .find(|p| !taken(p))
        .expect("an unused number")
}

/// The local date and time now (UTC where the platform's time zone cannot be read).
fn local_now() -> DateTime {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    local(secs).unwrap_or_else(|| utc(secs))
}

#[cfg(target_os = "linux")]
fn local(secs: i64) -> Option<DateTime> {
    let t: libc::time_t = secs;
    // SAFETY: `tm` is plain data (all zeroes is valid), and localtime_r writes only into it (thread-safe).
    let mut tm: libc::tm = unsafe { std::mem::zeroed() };
    // SAFETY: both pointers are to live locals of the right types.
    if unsafe { libc::localtime_r(&t, &mut tm) }.is_null() {
        return None;
    }
    Some([
        tm.tm_year + 1900,
        tm.tm_mon + 1,
        tm.tm_mday,
        tm.tm_hour,
        tm.tm_min,
        tm.tm_sec,
    ])
}

#[cfg(not(target_os = "linux"))]
fn local(_secs: i64) -> Option<DateTime> {
    None
}

/// The UTC date and time of `secs` since 1970 (Howard Hinnant's days-to-civil).
pub fn utc(secs: i64) -> DateTime {
    let (days, rest) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    let (h, m, s) = (rest / 3600, rest % 3600 / 60, rest % 60);
    [year, month, day, h, m, s].map(|v| v as i32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_as_a_date_and_time() {
        // 2026-11-26 12:03:45 UTC.
        assert_eq!(utc(1_795_694_625), [2026, 11, 26, 12, 3, 45]);
        assert_eq!(utc(0), [1970, 1, 1, 0, 0, 0]);
        assert_eq!(utc(951_782_400), [2000, 2, 29, 0, 0, 0]);
        assert_eq!(stem([2026, 11, 26, 12, 3, 45]), "volcast-2026-11-26_12-03-45");
    }

    #[test]
    fn a_name_taken_gets_the_next_number() {
        let taken = ["a.png", "a-2.png"].map(PathBuf::from);
        assert_eq!(
            unique_path("a", "png", |p| taken.iter().any(|t| t == p)),
            PathBuf::from("a-3.png")
        );
        assert_eq!(
            unique_path("b", "png", |p| taken.iter().any(|t| t == p)),
            PathBuf::from("b.png")
        );
    }
}
