//! A minimal `.npy` reader for the robot-side command line: little-endian float32, float64,
//! int16 or 8-bit unsigned (a camera's frames, as `pvt3 import` keeps them), C order. Small enough to keep the runtime free of array and zip crates.

use crate::{Error, Result};

/// Reads an `.npy` file's shape and values (as f32).
pub fn read_npy(path: &std::path::Path) -> Result<(Vec<usize>, Vec<f32>)> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| Error::Io { path: name.clone(), source })?;
    let bad = |why: &str| Error::Npy { path: name.clone(), reason: why.to_string() };
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(bad("not an .npy file"));
    }
    let (header_len, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize, 12),
        _ => return Err(bad("unsupported .npy version")),
    };
    let header = std::str::from_utf8(bytes.get(start..start + header_len).ok_or_else(|| bad("truncated header"))?)
        .map_err(|_| bad("header is not text"))?;
    let field = |key: &str| header.split(&format!("'{key}':")).nth(1).map(str::trim);
    let descr = field("descr").and_then(|d| d.split('\'').nth(1)).ok_or_else(|| bad("no dtype"))?;
    if field("fortran_order").is_some_and(|f| f.starts_with("True")) {
        return Err(bad("Fortran order is not supported; save with C order"));
    }
    let shape_text = field("shape").and_then(|s| s.strip_prefix('(')).and_then(|s| s.split(')').next()).ok_or_else(|| bad("no shape"))?;
    let shape: Vec<usize> = shape_text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().map_err(|_| bad("malformed shape")))
        .collect::<Result<_>>()?;
    let data = &bytes[start + header_len..];
    let count: usize = shape.iter().product();
    let (width, convert): (usize, fn(&[u8]) -> f32) = match descr {
        "<f4" => (4, |b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        "<f8" => (8, |b| f64::from_le_bytes(b.try_into().expect("8 bytes")) as f32),
        "<i2" => (2, |b| i16::from_le_bytes([b[0], b[1]]) as f32),
        "|u1" => (1, |b| f32::from(b[0])),
        other => return Err(bad(&format!("dtype {other} is not supported (use float32, float64, int16 or uint8)"))),
    };
    if data.len() != count * width {
        return Err(bad(&format!("holds {} bytes of data; shape {shape:?} needs {}", data.len(), count * width)));
    }
    Ok((shape, data.chunks_exact(width).map(convert).collect()))
}
