//! Instants: UTC, UT1 and TT from an RFC 3339 timestamp.
//!
//! **Model.** A [`Utc`] is the count of SI seconds since J2000.0 expressed
//! in UTC, 2000-01-01T12:00:00 UTC, with every UTC day 86 400 s long: the
//! Julian Date in UTC is `2451545 + s / 86400`. A leap second
//! (`23:59:60`) is read as the first second of the next day.
//!
//! - **UT1** is taken as UTC: `|UT1 - UTC| < 0.9 s` by the definition of
//!   UTC (IERS Conventions 2010, section 5.5.1), 0.004 degrees of the sky's
//!   rotation at most; the IERS' measured `UT1 - UTC` is not read.
//! - **TT** is `TAI + 32.184 s`, `TAI - UTC` from the leap-second table of
//!   IERS Bulletin C ([`tai_minus_utc_s`]): 37 s since 2017-01-01, the last
//!   entry (no leap second has been announced since). Before 1972, when
//!   UTC had fractional steps and drifts, the 1972 value (10 s) is used:
//!   an error of up to 10 s in TT before 1972, a few arcseconds of the
//!   Moon.
//!
//! **Text.** [`Utc::parse_rfc3339`] reads RFC 3339's `date-time` (Klyne and
//! Newman 2002, section 5.6): `YYYY-MM-DDTHH:MM:SS[.frac](Z|+HH:MM|-HH:MM)`,
//! `t` and `z` in lower case allowed; anything else is refused with a
//! message naming the part that is wrong. Years 1900 to 2100 only: the
//! models of this module (Meeus' series, the IAU 1976/1980 precession and
//! nutation) are fitted near J2000.

use thiserror::Error;

/// Seconds in a day.
pub const SECONDS_PER_DAY: f64 = 86_400.0;
/// The Julian Date of J2000.0 (2000-01-01T12:00:00).
pub const JD_J2000: f64 = 2_451_545.0;
/// TT - TAI, seconds.
pub const TT_MINUS_TAI_S: f64 = 32.184;

/// Why a timestamp was refused.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum TimeError {
    /// The text is not RFC 3339's `date-time`.
    #[error("{text:?} is not an RFC 3339 date-time (YYYY-MM-DDTHH:MM:SS[.frac]Z or +HH:MM): {what}")]
    Syntax { text: String, what: String },
    /// A field is out of its range (month 13, 31 April, hour 24...).
    #[error("{text:?}: {what}")]
    Range { text: String, what: String },
    /// The year is outside 1900-2100, where the sky's models hold.
    #[error("{text:?}: year {year} is outside 1900-2100, where the sky's models are fitted")]
    Year { text: String, year: i64 },
    /// An instant that is not finite.
    #[error("the instant {0} s from J2000 is not finite")]
    NotFinite(f64),
}

/// An instant, in UTC seconds since J2000.0 (2000-01-01T12:00:00 UTC).
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
pub struct Utc {
    /// Seconds since 2000-01-01T12:00:00 UTC, every day 86 400 s.
    pub seconds_since_j2000: f64,
}

/// Days from 1970-01-01 to the proleptic Gregorian date (y, m, d)
/// (Hinnant's `days_from_civil`).
pub fn days_from_civil(y: i64, m: u32, d: u32) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m as i64 + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d as i64 - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// The proleptic Gregorian date of a day count from 1970-01-01.
pub fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (if m <= 2 { yoe + era * 400 + 1 } else { yoe + era * 400 }, m, d)
}

fn is_leap(y: i64) -> bool {
    (y % 4 == 0 && y % 100 != 0) || y % 400 == 0
}

fn days_in_month(y: i64, m: u32) -> u32 {
    match m {
        2 if is_leap(y) => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

/// Days from 1970-01-01 to 2000-01-01.
const UNIX_DAYS_2000: i64 = 10_957;

/// UTC seconds since J2000 of midnight starting the date.
fn midnight_since_j2000(y: i64, m: u32, d: u32) -> f64 {
    (days_from_civil(y, m, d) - UNIX_DAYS_2000) as f64 * SECONDS_PER_DAY - 43_200.0
}

/// TAI - UTC from 1972 (IERS Bulletin C): (year, month of the step's first
/// day, seconds from then on).
const LEAP_SECONDS: &[(i64, u32, f64)] = &[
    (1972, 1, 10.0),
    (1972, 7, 11.0),
    (1973, 1, 12.0),
    (1974, 1, 13.0),
    (1975, 1, 14.0),
    (1976, 1, 15.0),
    (1977, 1, 16.0),
    (1978, 1, 17.0),
    (1979, 1, 18.0),
    (1980, 1, 19.0),
    (1981, 7, 20.0),
    (1982, 7, 21.0),
    (1983, 7, 22.0),
    (1985, 7, 23.0),
    (1988, 1, 24.0),
    (1990, 1, 25.0),
    (1991, 1, 26.0),
    (1992, 7, 27.0),
    (1993, 7, 28.0),
    (1994, 7, 29.0),
    (1996, 1, 30.0),
    (1997, 7, 31.0),
    (1999, 1, 32.0),
    (2006, 1, 33.0),
    (2009, 1, 34.0),
    (2012, 7, 35.0),
    (2015, 7, 36.0),
    (2017, 1, 37.0),
];

/// TAI - UTC at an instant, seconds: the leap-second table, its first
/// value (10 s) before 1972.
pub fn tai_minus_utc_s(t: Utc) -> f64 {
    let mut value = LEAP_SECONDS[0].2;
    for &(y, m, v) in LEAP_SECONDS {
        if t.seconds_since_j2000 >= midnight_since_j2000(y, m, 1) {
            value = v;
        }
    }
    value
}

fn syntax(text: &str, what: impl Into<String>) -> TimeError {
    TimeError::Syntax { text: text.to_string(), what: what.into() }
}

fn range(text: &str, what: impl Into<String>) -> TimeError {
    TimeError::Range { text: text.to_string(), what: what.into() }
}

/// `n` ASCII digits at `at` as a number, or a syntax error naming `field`.
fn digits(text: &str, b: &[u8], at: usize, n: usize, field: &str) -> Result<u32, TimeError> {
    let part = b.get(at..at + n).ok_or_else(|| syntax(text, format!("the {field} is cut short")))?;
    if !part.iter().all(u8::is_ascii_digit) {
        return Err(syntax(text, format!("the {field} must be {n} digits")));
    }
    Ok(part.iter().fold(0, |acc, &c| acc * 10 + (c - b'0') as u32))
}

fn expect(text: &str, b: &[u8], at: usize, what: u8, after: &str) -> Result<(), TimeError> {
    match b.get(at) {
        Some(&c) if c == what => Ok(()),
        _ => Err(syntax(text, format!("expected '{}' after the {after}", what as char))),
    }
}

impl Utc {
    /// The instant `seconds` after J2000.0 (UTC), refused if not finite.
    pub fn from_seconds_since_j2000(seconds: f64) -> Result<Utc, TimeError> {
        if !seconds.is_finite() {
            return Err(TimeError::NotFinite(seconds));
        }
        Ok(Utc { seconds_since_j2000: seconds })
    }

    /// The instant of a Julian Date in UTC.
    pub fn from_jd_utc(jd: f64) -> Utc {
        Utc { seconds_since_j2000: (jd - JD_J2000) * SECONDS_PER_DAY }
    }

    /// Reads an RFC 3339 `date-time` (module doc).
    pub fn parse_rfc3339(text: &str) -> Result<Utc, TimeError> {
        let b = text.as_bytes();
        let year = digits(text, b, 0, 4, "year")? as i64;
        expect(text, b, 4, b'-', "year")?;
        let month = digits(text, b, 5, 2, "month")?;
        expect(text, b, 7, b'-', "month")?;
        let day = digits(text, b, 8, 2, "day")?;
        match b.get(10) {
            Some(b'T') | Some(b't') => {}
            _ => return Err(syntax(text, "expected 'T' between the date and the time")),
        }
        let hour = digits(text, b, 11, 2, "hour")?;
        expect(text, b, 13, b':', "hour")?;
        let minute = digits(text, b, 14, 2, "minute")?;
        expect(text, b, 16, b':', "minute")?;
        let second = digits(text, b, 17, 2, "second")?;
        let mut at = 19;
        let mut fraction = 0.0;
        if b.get(at) == Some(&b'.') {
            let start = at + 1;
            at = start;
            while b.get(at).is_some_and(u8::is_ascii_digit) {
                at += 1;
            }
            if at == start {
                return Err(syntax(text, "the fraction of a second needs a digit after '.'"));
            }
            fraction = format!("0.{}", &text[start..at]).parse::<f64>().expect("digits parse");
        }
        let offset_s = match b.get(at) {
            Some(b'Z') | Some(b'z') => {
                at += 1;
                0i64
            }
            Some(&sign @ (b'+' | b'-')) => {
                let oh = digits(text, b, at + 1, 2, "offset's hours")?;
                expect(text, b, at + 3, b':', "offset's hours")?;
                let om = digits(text, b, at + 4, 2, "offset's minutes")?;
                if oh > 23 || om > 59 {
                    return Err(range(text, format!("the offset {oh:02}:{om:02} is out of range")));
                }
                at += 6;
                let s = (oh * 3600 + om * 60) as i64;
                if sign == b'+' {
                    s
                } else {
                    -s
                }
            }
            None => return Err(syntax(text, "the offset is missing (Z or +HH:MM or -HH:MM)")),
            Some(_) => return Err(syntax(text, "the offset must be Z, +HH:MM or -HH:MM")),
        };
        if at != b.len() {
            return Err(syntax(text, format!("unexpected {:?} after the offset", &text[at..])));
        }
        if !(1900..=2100).contains(&year) {
            return Err(TimeError::Year { text: text.to_string(), year });
        }
        if !(1..=12).contains(&month) {
            return Err(range(text, format!("month {month} is not 1-12")));
        }
        if day < 1 || day > days_in_month(year, month) {
            return Err(range(text, format!("day {day} is not in {year}-{month:02}")));
        }
        if hour > 23 || minute > 59 || second > 60 {
            return Err(range(text, format!("the time {hour:02}:{minute:02}:{second:02} is out of range")));
        }
        let seconds = midnight_since_j2000(year, month, day) + (hour * 3600 + minute * 60 + second) as f64 + fraction - offset_s as f64;
        Ok(Utc { seconds_since_j2000: seconds })
    }

    /// The instant as RFC 3339 in UTC (`Z`), to the millisecond, the
    /// fraction written only when it is not zero.
    pub fn to_rfc3339(&self) -> String {
        let ms = (self.seconds_since_j2000 * 1000.0).round() as i64 + 43_200_000;
        let day = ms.div_euclid(86_400_000);
        let ms_of_day = ms.rem_euclid(86_400_000);
        let (y, m, d) = civil_from_days(day + UNIX_DAYS_2000);
        let (h, rest) = (ms_of_day / 3_600_000, ms_of_day % 3_600_000);
        let (mi, rest) = (rest / 60_000, rest % 60_000);
        let (s, milli) = (rest / 1000, rest % 1000);
        if milli == 0 {
            format!("{y:04}-{m:02}-{d:02}T{h:02}:{mi:02}:{s:02}Z")
        } else {
            format!("{y:04}-{m:02}-{d:02}T{h:02}:{mi:02}:{s:02}.{milli:03}Z")
        }
    }

    /// The instant `seconds` later.
    pub fn plus_seconds(&self, seconds: f64) -> Utc {
        Utc { seconds_since_j2000: self.seconds_since_j2000 + seconds }
    }

    /// The Julian Date in UTC.
    pub fn jd_utc(&self) -> f64 {
        JD_J2000 + self.seconds_since_j2000 / SECONDS_PER_DAY
    }

    /// The Julian Date in UT1, taken as UTC (module doc).
    pub fn jd_ut1(&self) -> f64 {
        self.jd_utc()
    }

    /// The Julian Date in TT: UTC + (TAI - UTC) + 32.184 s.
    pub fn jd_tt(&self) -> f64 {
        JD_J2000 + (self.seconds_since_j2000 + tai_minus_utc_s(*self) + TT_MINUS_TAI_S) / SECONDS_PER_DAY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn j2000_and_its_julian_dates() {
        let t = Utc::parse_rfc3339("2000-01-01T12:00:00Z").unwrap();
        assert_eq!(t.seconds_since_j2000, 0.0);
        assert_eq!(t.jd_ut1(), JD_J2000);
        // TT - UTC = 32 + 32.184 s in 2000.
        assert!((t.jd_tt() - JD_J2000 - 64.184 / SECONDS_PER_DAY).abs() < 1e-9);
        let later = Utc::parse_rfc3339("2026-12-07T22:30:00Z").unwrap();
        assert!((later.jd_tt() - later.jd_utc() - 69.184 / SECONDS_PER_DAY).abs() < 1e-9);
        // Before 1972: the 1972 value.
        let early = Utc::parse_rfc3339("1950-01-01T00:00:00Z").unwrap();
        assert_eq!(tai_minus_utc_s(early), 10.0);
        let step = Utc::parse_rfc3339("2016-12-31T23:59:59.5Z").unwrap();
        assert_eq!(tai_minus_utc_s(step), 36.0);
        assert_eq!(tai_minus_utc_s(step.plus_seconds(0.5)), 37.0);
    }

    #[test]
    fn offsets_fractions_and_case() {
        let z = Utc::parse_rfc3339("2026-12-07T22:30:00Z").unwrap();
        for same in ["2026-12-07t22:30:00z", "2026-12-07T23:30:00+01:00", "2026-12-07T20:00:00-02:30"] {
            assert_eq!(Utc::parse_rfc3339(same).unwrap(), z, "{same}");
        }
        let f = Utc::parse_rfc3339("2026-12-07T22:30:00.25Z").unwrap();
        assert!((f.seconds_since_j2000 - z.seconds_since_j2000 - 0.25).abs() < 1e-6);
        assert_eq!(z.to_rfc3339(), "2026-12-07T22:30:00Z");
        assert_eq!(f.to_rfc3339(), "2026-12-07T22:30:00.250Z");
        assert_eq!(z.plus_seconds(-86_400.0 * 365.0).to_rfc3339(), "2025-12-07T22:30:00Z");
        // Julian Date of a published instant (Meeus, Example 7.a): 1957
        // October 4.81 is JD 2436116.31.
        let sputnik = Utc::parse_rfc3339("1957-10-04T19:26:24Z").unwrap();
        assert!((sputnik.jd_utc() - 2_436_116.31).abs() < 1e-9);
        let leap = Utc::parse_rfc3339("2016-12-31T23:59:60Z").unwrap();
        assert_eq!(leap.to_rfc3339(), "2017-01-01T00:00:00Z");
    }

    #[test]
    fn refusals_name_what_is_wrong() {
        let cases = [
            ("2026-12-07 22:30:00Z", "'T'"),
            ("2026-12-07T22:30:00", "offset is missing"),
            ("2026-12-07T22:30Z", "after the minute"),
            ("2026-13-07T22:30:00Z", "month 13"),
            ("2026-02-29T22:30:00Z", "day 29"),
            ("2026-12-07T24:30:00Z", "out of range"),
            ("2026-12-07T22:30:00.Z", "digit after '.'"),
            ("2026-12-07T22:30:00+0100", "':'"),
            ("2026-12-07T22:30:00Zjunk", "unexpected"),
            ("2026-12-7T22:30:00Z", "day must be 2 digits"),
            ("1899-12-31T23:00:00Z", "1900-2100"),
            ("2101-01-01T00:00:00Z", "1900-2100"),
            ("", "year"),
        ];
        for (text, needle) in cases {
            let e = Utc::parse_rfc3339(text).expect_err(text).to_string();
            assert!(e.contains(needle), "{text}: {e}");
        }
        assert!(Utc::from_seconds_since_j2000(f64::NAN).is_err());
    }

    #[test]
    fn civil_days_round_trip() {
        for z in (-30_000..60_000).step_by(37) {
            let (y, m, d) = civil_from_days(z);
            assert_eq!(days_from_civil(y, m, d), z);
        }
        assert_eq!(days_from_civil(2000, 1, 1), UNIX_DAYS_2000);
    }
}
