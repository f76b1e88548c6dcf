//! Parsers of flag values: numbers within a range, sizes (`4GiB`), points (`x,y,z`), lights
//! (`x,y,z,intensity`), colours (`r,g,b`), up directions and PNG paths; and [`BadUsage`], a bad command line found
//! after parsing.
//!
//! Every numeric flag goes through [`between`] (or [`real`], [`size`]), so a value that is out of
//! range, negative or not a number gets the same one-line message whatever its spelling (`--tiles
//! 0`, `--tiles -5`, `--tiles=-5`, `--tiles abc`): `--tiles must be between 1 and 65536, got 0`,
//! as a bad command line (exit 2, with clap's usage hint).

use clap::error::ErrorKind;
use clap::{Arg, Command};
use std::ffi::OsStr;
use std::fmt::Display;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// The largest `--directions`: a lattice of N = 4096 (`BakeConfig::validate`; a unit test holds
/// the two together).
pub const MAX_DIRECTIONS: u32 = 33_554_433;
/// The largest `--tiles`.
pub const MAX_TILES: u32 = 65_536;
/// The largest `--max-depth` of a bake: the format's limit (`formats/vlf.md` §5.2).
pub const MAX_BSP_DEPTH: u32 = vlf_bake::params::MAX_DEPTH;
/// The most worker threads a command accepts; more than the cores available are clamped to them.
pub const MAX_THREADS: usize = 1024;
/// The largest image side of `render` and `rays`: width × height then always fits the u32 ray
/// count of a rays file's reader.
pub const MAX_IMAGE_SIDE: u32 = vlf_render::setup::MAX_SIDE;
/// The most triangles `gen` writes: a field's triangle ids are u32, with `u32::MAX` for a miss.
pub const MAX_TRIANGLES: u64 = u32::MAX as u64;

/// A command line that parsed but asks for something impossible (a combination of flags, or a
/// flag whose range depends on another): `main` prints it as clap prints its errors, exit 2.
#[derive(Debug)]
pub struct BadUsage(pub String);

impl Display for BadUsage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadUsage {}

/// The flag as the user spells it (`--tiles`), for messages.
fn flag_name(arg: Option<&Arg>) -> String {
    match arg {
        Some(a) => match (a.get_long(), a.get_short()) {
            (Some(long), _) => format!("--{long}"),
            (None, Some(short)) => format!("-{short}"),
            (None, None) => a.get_id().to_string().to_uppercase(),
        },
        None => "the value".to_owned(),
    }
}

/// clap's error for `message`, with its usage line and help hint: exit code 2.
fn usage_error(cmd: &Command, message: String) -> clap::Error {
    clap::Error::raw(ErrorKind::ValueValidation, message).format(&mut cmd.clone())
}

/// A number between `min` and `max`, both included (see [`between`]).
#[derive(Clone, Copy, Debug)]
pub struct Between<T> {
    min: T,
    max: T,
}

/// A number between `min` and `max`, both included: `--tiles must be between 1 and 65536, got
/// 0` for anything else, including negative numbers and words.
pub fn between<T>(min: T, max: T) -> Between<T> {
    Between { min, max }
}

impl<T> clap::builder::TypedValueParser for Between<T>
where
    T: FromStr + PartialOrd + Display + Copy + Send + Sync + 'static,
{
    type Value = T;

    fn parse_ref(&self, cmd: &Command, arg: Option<&Arg>, value: &OsStr) -> Result<T, clap::Error> {
        let text = value.to_string_lossy();
        self.check(&flag_name(arg), &text, "").map_err(|e| usage_error(cmd, e.0))
    }
}

impl<T: FromStr + PartialOrd + Display + Copy> Between<T> {
    /// `text` as a number in the range, or the message of [`between`] for the flag `flag`, with
    /// `context` after the range (` for a grid (...)`): for a flag whose range depends on another,
    /// checked after parsing.
    pub fn check(&self, flag: &str, text: &str, context: &str) -> Result<T, BadUsage> {
        match text.trim().parse::<T>() {
            Ok(v) if v >= self.min && v <= self.max => Ok(v),
            _ => Err(BadUsage(format!("{flag} must be between {} and {}{context}, got {text}", self.min, self.max))),
        }
    }
}

/// A finite real number between `min` and `max`, each bound included or `excluded` (see [`real`]).
#[derive(Clone, Copy, Debug)]
pub struct Real {
    min: f64,
    min_excluded: bool,
    max: f64,
    max_excluded: bool,
}

/// A finite real number between `min` and `max`; `(true, _)` excludes `min`, `(_, true)` excludes
/// `max`: `--fov must be between 0 (excluded) and 180 (excluded), got 200`.
pub fn real(min: f64, max: f64, excluded: (bool, bool)) -> Real {
    Real { min, min_excluded: excluded.0, max, max_excluded: excluded.1 }
}

impl Real {
    fn contains(&self, v: f64) -> bool {
        let above = if self.min_excluded { v > self.min } else { v >= self.min };
        let below = if self.max_excluded { v < self.max } else { v <= self.max };
        v.is_finite() && above && below
    }
}

impl clap::builder::TypedValueParser for Real {
    type Value = f64;

    fn parse_ref(&self, cmd: &Command, arg: Option<&Arg>, value: &OsStr) -> Result<f64, clap::Error> {
        let text = value.to_string_lossy();
        match text.trim().parse::<f64>() {
            Ok(v) if self.contains(v) => Ok(v),
            _ => {
                let bound = |v: f64, excluded: bool| if excluded { format!("{v} (excluded)") } else { format!("{v}") };
                Err(usage_error(
                    cmd,
                    format!(
                        "{} must be between {} and {}, got {text}",
                        flag_name(arg),
                        bound(self.min, self.min_excluded),
                        bound(self.max, self.max_excluded)
                    ),
                ))
            }
        }
    }
}

/// A size in bytes (see [`parse_size`]): `--max-bytes must be a size between 1 B and 16 EiB - 1 B
/// (such as 4GiB, 512MiB or 1e9), got banana: …`.
#[derive(Clone, Copy, Debug)]
pub struct Size;

/// A size in bytes, with the message shape of [`between`].
pub fn size() -> Size {
    Size
}

impl clap::builder::TypedValueParser for Size {
    type Value = u64;

    fn parse_ref(&self, cmd: &Command, arg: Option<&Arg>, value: &OsStr) -> Result<u64, clap::Error> {
        let text = value.to_string_lossy();
        parse_size(&text).map_err(|why| {
            usage_error(
                cmd,
                format!(
                    "{} must be a size between 1 B and 16 EiB - 1 B (such as 4GiB, 512MiB or 1e9), got {text}: {why}",
                    flag_name(arg)
                ),
            )
        })
    }
}

/// A duration such as `30d`, `12h`, `90m` or `3600s` ([`vlf_bake::cache::parse_duration`]), with
/// the message shape of [`between`] for one that is negative or too large.
#[derive(Clone, Copy, Debug)]
pub struct Duration;

/// A duration (see [`Duration`]).
pub fn duration() -> Duration {
    Duration
}

/// The longest duration [`vlf_bake::cache::parse_duration`] takes: less than 10¹⁵ seconds.
const DURATION_SECONDS_BELOW: f64 = 1e15;

impl clap::builder::TypedValueParser for Duration {
    type Value = std::time::Duration;

    fn parse_ref(&self, cmd: &Command, arg: Option<&Arg>, value: &OsStr) -> Result<std::time::Duration, clap::Error> {
        let text = value.to_string_lossy();
        let why = match vlf_bake::cache::parse_duration(&text) {
            Ok(d) => return Ok(d),
            Err(why) => why,
        };
        let flag = flag_name(arg);
        // A well-formed number and unit that the range refused: its sign or its size is at fault.
        let t = text.trim();
        let (negative, magnitude) = match t.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, t.strip_prefix('+').unwrap_or(t)),
        };
        let split = magnitude.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(magnitude.len());
        let (number, unit) = magnitude.split_at(split);
        let plain = !number.trim().is_empty() && number.trim().bytes().all(|b| b.is_ascii_digit() || b == b'.');
        let known_unit = vlf_bake::cache::parse_duration(&format!("0{unit}")).is_ok();
        let message = match number.trim().parse::<f64>() {
            Ok(n) if plain && known_unit && negative && n > 0.0 => format!("{flag} must not be negative, got {text}"),
            Ok(_) if plain && known_unit && !negative => {
                let days = ((DURATION_SECONDS_BELOW - 1.0) / 86400.0).floor();
                format!(
                    "{flag} {text} is too large: the longest duration is {days}d ({} seconds, about 31 million years)",
                    days * 86400.0
                )
            }
            _ => format!("{flag} must be a duration such as 30d, 12h, 90m or 3600s, got {text}: {why}"),
        };
        Err(usage_error(cmd, message))
    }
}

/// The number at the start of `t` (digits, a point, an exponent such as `e9`) and the rest: the
/// `E` of `16EiB` is a unit, the `e` of `1e9` an exponent.
fn split_number(t: &str) -> (&str, &str) {
    let b = t.as_bytes();
    let digits = |mut i: usize| {
        while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
            i += 1;
        }
        i
    };
    let mut i = digits(usize::from(matches!(b.first(), Some(b'+' | b'-'))));
    if matches!(b.get(i), Some(b'e' | b'E')) {
        let sign = usize::from(matches!(b.get(i + 1), Some(b'+' | b'-')));
        if b.get(i + 1 + sign).is_some_and(u8::is_ascii_digit) {
            i = digits(i + 1 + sign);
        }
    }
    t.split_at(i)
}

/// Parses `4GiB`, `512MiB`, `100MB`, `1e9`, `123456`, up to 16 EiB - 1 B (`u64::MAX` bytes, the
/// largest size, which `18446744073709551615` gives exactly).
pub fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (num, unit) = split_number(t);
    let value: f64 = num.parse().map_err(|_| format!("`{s}` is not a size (try 4GiB, 512MiB or 1000000)"))?;
    let scale: u64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1,
        "k" | "kb" => 1_000,
        "m" | "mb" => 1_000_000,
        "g" | "gb" => 1_000_000_000,
        "t" | "tb" => 1_000_000_000_000,
        "p" | "pb" => 1_000_000_000_000_000,
        "e" | "eb" => 1_000_000_000_000_000_000,
        "kib" => 1 << 10,
        "mib" => 1 << 20,
        "gib" => 1 << 30,
        "tib" => 1 << 40,
        "pib" => 1 << 50,
        "eib" => 1 << 60,
        other => {
            return Err(format!(
                "unknown size unit `{other}` in `{s}` (use B, KB, MB, GB, TB, PB, EB, KiB, MiB, GiB, TiB, PiB or EiB)"
            ));
        }
    };
    let too_large = || format!("`{s}` is too large: the largest size is {} bytes (16 EiB - 1 B)", u64::MAX);
    // Whole numbers exactly (an f64 cannot hold every u64); the others through f64.
    let bytes = match num.trim_start_matches('+').parse::<u128>() {
        Ok(n) => n.checked_mul(scale as u128).and_then(|b| u64::try_from(b).ok()).ok_or_else(too_large)?,
        Err(_) if value.is_nan() || value <= 0.0 => return Err(format!("`{s}` is not a positive size")),
        Err(_) => {
            let bytes = value * scale as f64;
            // 2^64, the first f64 past u64::MAX.
            if bytes >= 18_446_744_073_709_551_616.0 {
                return Err(too_large());
            }
            bytes as u64
        }
    };
    if bytes == 0 {
        return Err(format!("`{s}` is not a positive size: the smallest is 1 byte"));
    }
    Ok(bytes)
}

/// Parses `x,y,z`.
pub fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let v = parse_numbers(s, 3)?;
    Ok([v[0], v[1], v[2]])
}

/// Parses an up direction `x,y,z`: three numbers, not all zero.
pub fn parse_up(s: &str) -> Result<[f64; 3], String> {
    let v = parse_vec3(s)?;
    if v.iter().all(|&c| c == 0.0) {
        return Err(format!("`{s}` is the zero vector, which points nowhere: give an up direction such as 0,1,0"));
    }
    Ok(v)
}

/// Parses `x,y,z,intensity`.
pub fn parse_light(s: &str) -> Result<[f64; 4], String> {
    let v = parse_numbers(s, 4)?;
    if v[3] < 0.0 {
        return Err(format!("`{s}`: the intensity must not be negative"));
    }
    Ok([v[0], v[1], v[2], v[3]])
}

/// Parses a colour `r,g,b`: three numbers from 0 to 1 (linear).
pub fn parse_colour(s: &str) -> Result<[f64; 3], String> {
    let v = parse_vec3(s)?;
    if let Some(i) = v.iter().position(|c| !(0.0..=1.0).contains(c)) {
        return Err(format!("component {} of `{s}`, {}, is outside 0 to 1 (a linear R,G,B colour)", i + 1, v[i]));
    }
    Ok(v)
}

/// `count` comma-separated finite numbers; a message names the component at fault (counted from 1).
fn parse_numbers(s: &str, count: usize) -> Result<Vec<f64>, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let mut v = Vec::with_capacity(parts.len());
    for (i, p) in parts.iter().enumerate() {
        match p.parse::<f64>() {
            Ok(x) => v.push(x),
            Err(_) => return Err(format!("component {} of `{s}`, `{p}`, is not a number", i + 1)),
        }
    }
    if v.len() != count {
        return Err(format!("`{s}` has {} numbers, expected {count} separated by commas", v.len()));
    }
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(format!("component {} of `{s}`, {}, is not a finite number", i + 1, parts[i]));
    }
    Ok(v)
}

/// Parses the path of a picture to write: a `.png` file (the one format `render` writes), or an
/// existing device or FIFO such as `/dev/stdout`, which is written through.
pub fn parse_png_path(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    if is_png_name(&path) || is_special_file(&path) {
        return Ok(path);
    }
    Err(format!("`{s}` does not end in .png: render writes PNG pictures only, so name the file NAME.png"))
}

fn is_png_name(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"))
}

/// An existing path that is neither a regular file nor a directory: a device, FIFO or socket.
pub fn is_special_file(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::builder::TypedValueParser;
    use vlf_bake::{BakeConfig, DepthPolicy};

    fn parse<P: TypedValueParser>(parser: P, value: &str) -> Result<P::Value, String> {
        let cmd = Command::new("vlf-bake");
        let arg = Arg::new("tiles").long("tiles");
        parser.parse_ref(&cmd, Some(&arg), OsStr::new(value)).map_err(|e| e.to_string())
    }

    #[test]
    fn numbers_out_of_range_get_one_message_whatever_their_spelling() {
        assert_eq!(parse(between(1u32, 65536), "16"), Ok(16));
        assert_eq!(parse(between(1u32, 65536), " 65536 "), Ok(65536));
        for bad in ["0", "-5", "abc", "65537", "1e3", "", "99999999999999999999"] {
            let message = parse(between(1u32, 65536), bad).unwrap_err();
            let first = message.lines().next().unwrap();
            assert_eq!(first, format!("error: --tiles must be between 1 and 65536, got {bad}"));
            assert!(message.contains("For more information, try '--help'."), "{message}");
        }
        assert_eq!(parse(real(0.0, 180.0, (true, true)), "50"), Ok(50.0));
        for bad in ["0", "180", "-1", "nan", "inf", "wide"] {
            let message = parse(real(0.0, 180.0, (true, true)), bad).unwrap_err();
            assert!(
                message
                    .starts_with(&format!("error: --tiles must be between 0 (excluded) and 180 (excluded), got {bad}")),
                "{message}"
            );
        }
        assert_eq!(parse(real(0.0, 10.0, (false, false)), "0"), Ok(0.0));
        assert!(parse(size(), "banana").unwrap_err().starts_with("error: --tiles must be a size"));
        assert_eq!(parse(size(), "4GiB"), Ok(4 << 30));
    }

    /// The command line's ranges are the library's: the bounds validate, one step past them does
    /// not.
    #[test]
    fn bake_ranges_agree_with_the_library() {
        let d = BakeConfig::default();
        let valid = |c: BakeConfig| c.validate().is_ok();
        assert!(
            valid(BakeConfig { directions: Some(3), ..d })
                && valid(BakeConfig { directions: Some(MAX_DIRECTIONS), ..d })
        );
        assert!(!valid(BakeConfig { directions: Some(2), ..d }));
        assert!(!valid(BakeConfig { directions: Some(MAX_DIRECTIONS + 1), ..d }));
        assert!(valid(BakeConfig { tiles: Some(1), ..d }) && valid(BakeConfig { tiles: Some(MAX_TILES), ..d }));
        assert!(!valid(BakeConfig { tiles: Some(0), ..d }) && !valid(BakeConfig { tiles: Some(MAX_TILES + 1), ..d }));
        let depth = |max_depth| BakeConfig { depth: DepthPolicy { leaf_size: 1, max_depth }, ..d };
        assert!(valid(depth(0)) && valid(depth(MAX_BSP_DEPTH)) && !valid(depth(MAX_BSP_DEPTH + 1)));
        assert!(!valid(BakeConfig { depth: DepthPolicy { leaf_size: 0, max_depth: 1 }, ..d }));
        // Every image fits the u32 ray count.
        assert!((MAX_IMAGE_SIDE as u64).pow(2) <= u32::MAX as u64);
    }

    #[test]
    fn sizes_take_decimal_and_binary_units_and_refuse_the_rest() {
        assert_eq!(parse_size("4GiB"), Ok(4 << 30));
        assert_eq!(parse_size("512 MiB"), Ok(512 << 20));
        assert_eq!(parse_size("100MB"), Ok(100_000_000));
        assert_eq!(parse_size("1e9"), Ok(1_000_000_000));
        assert_eq!(parse_size("123456"), Ok(123_456));
        assert_eq!(parse_size("16KiB"), Ok(16 << 10));
        assert!(parse_size("0").is_err());
        assert!(parse_size("-1MB").is_err());
        assert!(parse_size("3 parsecs").unwrap_err().contains("unknown size unit"));
        assert!(parse_size("lots").unwrap_err().contains("is not a size"));
        // The whole range the message gives, exactly, and its units.
        assert_eq!(parse_size("18446744073709551615"), Ok(u64::MAX));
        assert_eq!(parse_size("15EiB"), Ok(15 << 60));
        assert_eq!(parse_size("1e18"), Ok(1_000_000_000_000_000_000));
        assert_eq!(parse_size("2PiB"), Ok(2 << 50));
        for large in ["18446744073709551616", "16EiB", "1e30", "99999999999999999999999999999999999999999", "1e400"] {
            assert!(parse_size(large).unwrap_err().contains("is too large: the largest size is"), "{large}");
        }
        assert!(parse_size("0.1").unwrap_err().contains("the smallest is 1 byte"));
        assert!(parse_size("nan").unwrap_err().contains("is not a size"));
        assert!(parse_size("-1").unwrap_err().contains("is not a positive size"));
    }

    #[test]
    fn points_and_lights_are_comma_separated_finite_numbers() {
        assert_eq!(parse_vec3("1, -2.5,3"), Ok([1.0, -2.5, 3.0]));
        assert!(parse_vec3("1,2").unwrap_err().contains("expected 3"));
        assert!(parse_vec3("1,2,nan").is_err());
        assert_eq!(parse_vec3("NaN,0,0").unwrap_err(), "component 1 of `NaN,0,0`, NaN, is not a finite number");
        assert_eq!(
            parse_light("0,0,0,1e309").unwrap_err(),
            "component 4 of `0,0,0,1e309`, 1e309, is not a finite number"
        );
        assert_eq!(parse_vec3("1,x,3").unwrap_err(), "component 2 of `1,x,3`, `x`, is not a number");
        assert_eq!(parse_colour("0.5,1,0"), Ok([0.5, 1.0, 0.0]));
        assert!(parse_colour("2,0,0").unwrap_err().contains("component 1 of `2,0,0`, 2, is outside 0 to 1"));
        assert!(parse_colour("0,-1,0").unwrap_err().contains("component 2 of `0,-1,0`, -1, is outside 0 to 1"));
        assert_eq!(parse_light("0,1,0,20"), Ok([0.0, 1.0, 0.0, 20.0]));
        assert!(parse_light("0,1,0,-1").unwrap_err().contains("must not be negative"));
        assert_eq!(parse_up("0,0,1"), Ok([0.0, 0.0, 1.0]));
        assert!(parse_up("0,0,0").unwrap_err().contains("zero vector"));
        assert!(parse_up("0,-0,0").is_err());
    }

    #[test]
    fn durations_too_large_or_negative_say_so() {
        assert_eq!(parse(duration(), "30d"), Ok(std::time::Duration::from_secs(30 * 86400)));
        assert_eq!(parse(duration(), "11574074074d"), Ok(std::time::Duration::from_secs(11_574_074_074 * 86400)));
        let first = |v: &str| parse(duration(), v).unwrap_err().lines().next().unwrap().to_owned();
        assert_eq!(
            first("99999999999999d"),
            "error: --tiles 99999999999999d is too large: the longest duration is 11574074074d (999999999993600 \
             seconds, about 31 million years)"
        );
        assert_eq!(first("-1d"), "error: --tiles must not be negative, got -1d");
        assert!(first("1e3").contains("got 1e3: `1e3` is not a duration"), "{}", first("1e3"));
        assert!(first("-soon").contains("must be a duration"), "{}", first("-soon"));
    }

    #[test]
    fn pictures_are_png_files_or_devices() {
        assert_eq!(parse_png_path("out/a.png"), Ok(PathBuf::from("out/a.png")));
        assert_eq!(parse_png_path("A.PNG"), Ok(PathBuf::from("A.PNG")));
        for bad in ["x.jpg", "x", "png", "x.png.tmp"] {
            assert!(parse_png_path(bad).unwrap_err().contains("does not end in .png"), "{bad}");
        }
        #[cfg(unix)]
        assert_eq!(parse_png_path("/dev/null"), Ok(PathBuf::from("/dev/null")));
    }
}
