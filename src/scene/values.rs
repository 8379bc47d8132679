//! Values as a user types them (`--window`, `--iso`): in the data's own units (HU for a CT, z for a z-map), or as
//! a percentage of the data's range where written as one (`40%`). The renderer takes a value's place in the
//! range (0 at its minimum, 1 at its maximum), as sessions store it, so a session saved before units existed
//! looks the same.

/// A value in data units, or a percentage of the range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DataValue {
    Units(f64),
    Percent(f64),
}

impl DataValue {
    /// `-1000`, `0.5` (data units) or `40%`; a message naming `s` otherwise.
    pub fn parse(s: &str) -> Result<DataValue, String> {
        let t = s.trim();
        let (number, percent) = match t.strip_suffix('%') {
            Some(n) => (n.trim(), true),
            None => (t, false),
        };
        match number.parse::<f64>() {
            Ok(v) if v.is_finite() && percent => Ok(DataValue::Percent(v)),
            Ok(v) if v.is_finite() => Ok(DataValue::Units(v)),
            _ => Err(format!(
                "'{s}' must be a number in the data's units (e.g. -1000) or a percentage (e.g. 40%)"
            )),
        }
    }

    /// Its place in `range` (data units): 0 at the minimum, 1 at the maximum, beyond them outside it.
    pub fn fraction(self, range: [f64; 2]) -> f32 {
        match self {
            DataValue::Percent(p) => (p / 100.0) as f32,
            DataValue::Units(v) if range[1] > range[0] => ((v - range[0]) / (range[1] - range[0])) as f32,
            DataValue::Units(v) => f32::from(v > range[0]),
        }
    }

    /// The value in data units over `range`.
    pub fn units(self, range: [f64; 2]) -> f64 {
        match self {
            DataValue::Units(v) => v,
            DataValue::Percent(p) => range[0] + p / 100.0 * (range[1] - range[0]),
        }
    }
}

/// A note where every value of `values` is a bare number in [0, 1] while the data's range reaches well beyond it:
/// written before values were in data units, it now means a sliver of the range.
pub fn fraction_note(option: &str, values: &[DataValue], range: [f64; 2]) -> Option<String> {
    let bare = values
        .iter()
        .all(|v| matches!(v, DataValue::Units(u) if (0.0..=1.0).contains(u)));
    let wide = range[0] < -1.0 || range[1] > 2.0;
    (bare && wide && !values.is_empty()).then(|| {
        let percent: Vec<String> = values
            .iter()
            .map(|v| format!("{}%", (v.units(range) * 1e4).round() / 100.0))
            .collect();
        format!(
            "{option} is in the data's units, which here run from {} to {}; for a fraction of that range write \
             percentages ({option} {})",
            range[0],
            range[1],
            percent.join(",")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_and_percentages_find_their_place_in_the_range() {
        let ct = [-1024.0, 3071.0];
        let hu = DataValue::parse("-1024").unwrap();
        assert_eq!(hu.fraction(ct), 0.0);
        assert!((DataValue::parse("1000").unwrap().fraction(ct) - 2024.0 / 4095.0).abs() < 1e-6);
        assert_eq!(DataValue::parse(" 40% ").unwrap(), DataValue::Percent(40.0));
        assert!((DataValue::parse("40%").unwrap().fraction(ct) - 0.4).abs() < 1e-6);
        assert_eq!(DataValue::parse("50%").unwrap().units(ct), 1023.5);
        assert!(DataValue::parse("4o%").is_err() && DataValue::parse("inf").is_err() && DataValue::parse("").is_err());
        assert_eq!(DataValue::Units(5.0).fraction([5.0, 5.0]), 0.0, "a constant volume");
    }

    #[test]
    fn bare_fractions_over_wide_data_get_a_note() {
        let bare = [DataValue::Units(0.1), DataValue::Units(1.0)];
        let note = fraction_note("--window", &bare, [-1024.0, 3071.0]).expect("a note");
        assert!(note.contains("--window 10%,100%"), "{note}");
        assert!(
            fraction_note("--window", &bare, [0.0, 1.0]).is_none(),
            "data in [0, 1]: units are fractions"
        );
        let hu = [DataValue::Units(-100.0), DataValue::Units(300.0)];
        assert!(fraction_note("--window", &hu, [-1024.0, 3071.0]).is_none());
    }
}
