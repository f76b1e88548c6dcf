//! Parsers of flag values: sizes (`4GiB`), points (`x,y,z`) and lights (`x,y,z,intensity`).

/// Parses `4GiB`, `512MiB`, `100MB`, `1e9`, `123456`.
pub fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E').unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let value: f64 = num.trim().parse().map_err(|_| format!("`{s}` is not a size (try 4GiB, 512MiB or 1000000)"))?;
    let scale = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" => 1e3,
        "m" | "mb" => 1e6,
        "g" | "gb" => 1e9,
        "t" | "tb" => 1e12,
        "kib" => 1024.0,
        "mib" => 1024.0 * 1024.0,
        "gib" => 1024.0 * 1024.0 * 1024.0,
        "tib" => 1024.0f64.powi(4),
        other => return Err(format!("unknown size unit `{other}` in `{s}` (use B, KB, MB, GB, KiB, MiB, GiB)")),
    };
    let bytes = value * scale;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!("`{s}` is not a positive size"));
    }
    Ok(bytes as u64)
}

/// Parses `x,y,z`.
pub fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let v = parse_numbers(s, 3)?;
    Ok([v[0], v[1], v[2]])
}

/// Parses `x,y,z,intensity`.
pub fn parse_light(s: &str) -> Result<[f64; 4], String> {
    let v = parse_numbers(s, 4)?;
    if v[3] < 0.0 {
        return Err(format!("`{s}`: the intensity must not be negative"));
    }
    Ok([v[0], v[1], v[2], v[3]])
}

fn parse_numbers(s: &str, count: usize) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("`{s}` is not {count} comma-separated numbers"))?;
    if v.len() != count {
        return Err(format!("`{s}` has {} numbers, expected {count} separated by commas", v.len()));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

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
    }

    #[test]
    fn points_and_lights_are_comma_separated_finite_numbers() {
        assert_eq!(parse_vec3("1, -2.5,3"), Ok([1.0, -2.5, 3.0]));
        assert!(parse_vec3("1,2").unwrap_err().contains("expected 3"));
        assert!(parse_vec3("1,2,nan").is_err());
        assert_eq!(parse_light("0,1,0,20"), Ok([0.0, 1.0, 0.0, 20.0]));
        assert!(parse_light("0,1,0,-1").unwrap_err().contains("must not be negative"));
    }
}
