//! From a frame to bytes: sRGB pictures, false-colour pictures of the work per pixel, and PNG.

use crate::render::Frame;
use vlf_geom::TraceStats;

/// Linear to sRGB transfer (IEC 61966-2-1), for a value in `[0, 1]`.
fn srgb_encode(linear: f64) -> f64 {
    if linear <= 0.003_130_8 { 12.92 * linear } else { 1.055 * linear.powf(1.0 / 2.4) - 0.055 }
}

/// 8-bit sRGB of the frame's colours times `exposure`, clipped to `[0, 1]`; RGB, row by row.
pub fn to_srgb8(frame: &Frame, exposure: f64) -> Vec<u8> {
    let mut out = Vec::with_capacity(frame.color.len() * 3);
    for pixel in &frame.color {
        for &c in pixel {
            let v = (c as f64 * exposure).clamp(0.0, 1.0);
            // NaN (a damaged field's material) falls through clamp; `as` maps it to 0.
            out.push((srgb_encode(v) * 255.0 + 0.5) as u8);
        }
    }
    out
}

/// Which work a work image shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WorkMetric {
    /// Ray/triangle tests.
    TriangleTests,
    /// Cells visited: tiles for the field, nodes for the kd-tree.
    Cells,
    /// Leaves visited (field: 1D-BSP leaves; kd-tree: leaves).
    Leaves,
    /// Rays that reached the structure.
    Rays,
}

impl WorkMetric {
    pub fn of(self, w: &TraceStats) -> u64 {
        match self {
            WorkMetric::TriangleTests => w.triangle_tests,
            WorkMetric::Cells => w.cells,
            WorkMetric::Leaves => w.leaves,
            WorkMetric::Rays => w.rays,
        }
    }

    /// What the metric counts, for legends.
    pub fn describe(self) -> &'static str {
        match self {
            WorkMetric::TriangleTests => "ray/triangle tests",
            WorkMetric::Cells => "tiles visited",
            WorkMetric::Leaves => "leaves visited",
            WorkMetric::Rays => "rays traced",
        }
    }
}

/// A false-colour picture of the work per pixel, and its scale.
#[derive(Clone, Debug, PartialEq)]
pub struct WorkImage {
    /// 8-bit sRGB, RGB, row by row.
    pub rgb: Vec<u8>,
    /// The value shown at the top of the scale (white-yellow); 0 is black.
    pub scale_max: u64,
    /// The largest and mean value over the pixels.
    pub max: u64,
    pub mean: f64,
}

/// The "inferno" colour map (perceptually uniform, dark to bright), as 9 sRGB stops.
const INFERNO: [[f64; 3]; 9] = [
    [0.0, 0.0, 4.0],
    [31.0, 12.0, 72.0],
    [85.0, 15.0, 109.0],
    [136.0, 34.0, 106.0],
    [186.0, 54.0, 85.0],
    [227.0, 89.0, 51.0],
    [249.0, 140.0, 10.0],
    [249.0, 201.0, 50.0],
    [252.0, 255.0, 164.0],
];

/// The colour of `t` in `[0, 1]` on the inferno colour map (nine stops, linearly interpolated).
pub fn inferno(t: f64) -> [u8; 3] {
    let x = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * (INFERNO.len() - 1) as f64;
    let i = (x as usize).min(INFERNO.len() - 2);
    let f = x - i as f64;
    std::array::from_fn(|c| (INFERNO[i][c] + (INFERNO[i + 1][c] - INFERNO[i][c]) * f + 0.5) as u8)
}

/// The work of `metric` per pixel on a linear scale from 0 (black) to `scale_max` (white-yellow;
/// larger values are clipped). `scale_max` defaults to the 99th percentile of the frame's values,
/// so that a few extreme pixels (a glass ball's many bounces) do not turn the rest black; give the
/// same value to compare several frames.
pub fn work_image(frame: &Frame, metric: WorkMetric, scale_max: Option<u64>) -> WorkImage {
    let values: Vec<u64> = frame.work.iter().map(|w| metric.of(w)).collect();
    let max = values.iter().copied().max().unwrap_or(0);
    let mean = values.iter().map(|&v| v as f64).sum::<f64>() / values.len().max(1) as f64;
    let scale_max = scale_max.unwrap_or_else(|| percentile(&values, 0.99)).max(1);
    let rgb = values.iter().flat_map(|&v| inferno(v as f64 / scale_max as f64)).collect();
    WorkImage { rgb, scale_max, max, mean }
}

/// The value below which a fraction `q` of `values` lie (nearest rank); 0 for no values.
fn percentile(values: &[u64], q: f64) -> u64 {
    if values.is_empty() {
        return 0;
    }
    let mut sorted = values.to_vec();
    let k = ((sorted.len() - 1) as f64 * q).round() as usize;
    *sorted.select_nth_unstable(k).1
}

/// An upper bound on the memory of turning a frame of `width × height` pixels into a picture
/// ([`to_srgb8`], then [`encode_png`], whose output may grow to twice the stored size while it is
/// written) and, with `work`, into a work picture too ([`work_image`]: the values, a sorted copy
/// for the percentile, the colours and their PNG), all counted as if alive at once.
pub fn picture_bytes_at_most(width: u32, height: u32, work: bool) -> u64 {
    let pixels = width as u64 * height as u64;
    // Filtered rows of 8-bit RGB, which deflate at worst stores with well under 0.1% added.
    let rows = (3 * width as u64 + 1) * height as u64;
    let png = 2 * (rows + rows / 1000 + (64 << 10));
    let picture = 3 * pixels + png;
    if work { 2 * picture + 2 * size_of::<u64>() as u64 * pixels } else { picture }
}

/// A PNG of 8-bit sRGB pixels (RGB, row by row), tagged sRGB.
pub fn encode_png(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, png::EncodingError> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        encoder.set_compression(png::Compression::High);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(rgb)?;
        writer.finish()?;
    }
    Ok(bytes)
}

/// An animated PNG (APNG) of `frames`, each 8-bit RGB of `width × height`, shown `delay_ms`
/// milliseconds each and looped forever. Viewers without APNG support show the first frame.
pub fn encode_apng(width: u32, height: u32, frames: &[Vec<u8>], delay_ms: u16) -> Result<Vec<u8>, png::EncodingError> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        encoder.set_compression(png::Compression::High);
        encoder.set_animated(frames.len().max(1) as u32, 0)?;
        encoder.set_frame_delay(delay_ms, 1000)?;
        let mut writer = encoder.write_header()?;
        for rgb in frames {
            writer.write_image_data(rgb)?;
        }
        writer.finish()?;
    }
    Ok(bytes)
}

/// Width, height and 8-bit RGB pixels of a PNG (any colour type; alpha is dropped, grey expanded).
pub fn decode_png(bytes: &[u8]) -> Result<(u32, u32, Vec<u8>), png::DecodingError> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info()?;
    let mut buf = vec![0; reader.output_buffer_size().unwrap_or(0)];
    let info = reader.next_frame(&mut buf)?;
    buf.truncate(info.buffer_size());
    let channels = info.color_type.samples();
    let rgb = match info.color_type {
        png::ColorType::Rgb => buf,
        png::ColorType::Rgba => buf.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect(),
        png::ColorType::Grayscale | png::ColorType::GrayscaleAlpha => {
            buf.chunks_exact(channels).flat_map(|p| [p[0]; 3]).collect()
        }
        png::ColorType::Indexed => unreachable!("EXPAND turns palettes into RGB"),
    };
    Ok((info.width, info.height, rgb))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_encoding_and_png_round_trip() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-12);
        assert!((srgb_encode(0.214) - 0.5).abs() < 1e-3, "mid grey");
        let rgb: Vec<u8> = (0..6 * 4 * 3).map(|i| (i * 7) as u8).collect();
        let png = encode_png(6, 4, &rgb).unwrap();
        assert_eq!(decode_png(&png).unwrap(), (6, 4, rgb));
    }

    #[test]
    fn noise_fits_the_memory_bound_of_a_picture() {
        let (w, h) = (97u32, 61u32);
        let mut state = 1u64;
        let rgb: Vec<u8> = (0..w * h * 3)
            .map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (state >> 56) as u8
            })
            .collect();
        let png = encode_png(w, h, &rgb).unwrap();
        let bound = picture_bytes_at_most(w, h, false);
        assert!((rgb.len() + 2 * png.len()) as u64 <= bound, "{} + 2 × {} > {bound}", rgb.len(), png.len());
        assert!(picture_bytes_at_most(w, h, true) > 2 * bound);
    }

    #[test]
    fn the_work_scale_runs_from_black_to_the_top_colour() {
        assert_eq!(inferno(0.0), [0, 0, 4]);
        assert_eq!(inferno(1.0), [252, 255, 164]);
        assert_eq!(inferno(f64::NAN), inferno(0.0));
        assert_eq!(percentile(&[5, 1, 4, 2, 3], 0.5), 3);
        assert_eq!(percentile(&[], 0.99), 0);
    }
}
