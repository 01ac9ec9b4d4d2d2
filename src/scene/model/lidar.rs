//! LAS and LAZ lidar point clouds (the `las` crate, LAZ through `laz`): positions (the file's
//! scale and offset applied) and colours where the point format has them. Lidar points carry
//! no normals: the splats' normals come from their neighbours (`normals::pca_normals`).
//! Colours are 16-bit in the standard; files whose colours never exceed 255 hold 8-bit values,
//! and are read as such. A point whose position is not finite or past f32's range is skipped
//! and counted (`Reading`); a header whose points would lie past the file's end is an error
//! giving both, before any is read.

use std::io::Cursor;
use std::path::Path;

use glam::Vec3;

use super::Mesh;
use super::reading::{LeftOut, Reading, point_f32};
use crate::error::{Error, Result};

/// Points read per batch: the reader never holds more than one batch of raw records.
const BATCH: u64 = 1 << 20;
/// Most bytes of raw records one batch may take (a header may claim records of 64 KiB).
const BATCH_BYTES: u64 = 64 << 20;

/// Most points a header may announce for the bytes the file has: an uncompressed record
/// takes its record length; a LAZ record compresses to no less than about a byte.
fn plausible(points: u64, record: u64, bytes: usize, compressed: bool) -> bool {
    let per_point = if compressed { 1 } else { record.max(1) };
    points.saturating_mul(per_point) <= bytes as u64
}

/// The little-endian integers of a LAS header at byte `o`, where the file has them.
fn u16_at(bytes: &[u8], o: usize) -> Option<u16> {
    Some(u16::from_le_bytes(bytes.get(o..o + 2)?.try_into().ok()?))
}

fn u32_at(bytes: &[u8], o: usize) -> Option<u32> {
    Some(u32::from_le_bytes(bytes.get(o..o + 4)?.try_into().ok()?))
}

fn i64_at(bytes: &[u8], o: usize) -> Option<i64> {
    Some(i64::from_le_bytes(bytes.get(o..o + 8)?.try_into().ok()?))
}

/// Whether the header's point format (byte 104) has the LAZ compression bit.
fn is_compressed(bytes: &[u8]) -> bool {
    bytes.get(104).is_some_and(|f| f & 0x80 != 0)
}

/// The offset of the point data the header gives (bytes 96–99).
fn point_data_offset(bytes: &[u8]) -> Option<u64> {
    u32_at(bytes, 96).map(u64::from)
}

/// Whether a LAZ file's chunk table announces no more chunks than the file has bytes: the
/// LAZ reader sizes its table by that count before reading it, so a damaged count would ask
/// for any amount of memory. The table's offset is the first 8 bytes of the point data (or, if
/// they are −1, the file's last 8 bytes); other files pass.
fn laz_chunks_plausible(bytes: &[u8]) -> bool {
    let Some(points_at) = point_data_offset(bytes).filter(|_| is_compressed(bytes)) else {
        return true;
    };
    let table = match i64_at(bytes, points_at as usize) {
        Some(-1) => (bytes.len().checked_sub(8)).and_then(|o| i64_at(bytes, o)),
        other => other,
    };
    match table
        .and_then(|t| usize::try_from(t).ok())
        .and_then(|t| u32_at(bytes, t + 4))
    {
        Some(chunks) => chunks as usize <= bytes.len(),
        None => true,
    }
}

/// A reader's error in words: a read past the end names the file's size.
fn read_error(e: las::Error, size: usize) -> String {
    match e {
        las::Error::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            format!("the file ends (at byte {size}) before what its header announces")
        }
        e => e.to_string(),
    }
}

/// Whether a compressed file's LAZ description (the `laszip encoded` record 22204) lists at
/// least one item: the LAZ reader takes the first without asking (it panicked on a fuzzed
/// file). Files that are not compressed, or hold no such record, pass: the reader judges them.
fn laz_items_listed(bytes: &[u8]) -> bool {
    let (Some(header), Some(records)) = (u16_at(bytes, 94), u32_at(bytes, 100)) else {
        return true;
    };
    if !is_compressed(bytes) {
        return true;
    }
    // Each variable-length record: 54 bytes of header (its user ID at 2, its record ID at 18,
    // its length at 20), then its data; the LAZ item count is at byte 32 of the data.
    let mut at = header as usize;
    for _ in 0..records.min(1 << 16) {
        let (Some(id), Some(len)) = (u16_at(bytes, at + 18), u16_at(bytes, at + 20)) else {
            return true;
        };
        let user = bytes.get(at + 2..at + 18).unwrap_or_default();
        if user.starts_with(b"laszip encoded") && id == 22204 {
            return len >= 34 && u16_at(bytes, at + 54 + 32).is_some_and(|n| n > 0);
        }
        at += 54 + len as usize;
    }
    true
}

/// Parses a LAS or LAZ file's `bytes` (the reader keeps them: no copy of a large file); a
/// panic of the LAS/LAZ crates on a damaged file is an error (`reading::guarded`).
pub fn parse(path: &Path, bytes: Vec<u8>, reading: &Reading) -> Result<Mesh> {
    super::reading::guarded(path, || parse_unguarded(path, bytes, reading))
}

fn parse_unguarded(path: &Path, bytes: Vec<u8>, reading: &Reading) -> Result<Mesh> {
    let size = bytes.len();
    let bad = |at: &str, e: las::Error| Error::parse(path, at, read_error(e, size));
    if !laz_chunks_plausible(&bytes) {
        return Err(Error::parse(
            path,
            "chunk table",
            "its LAZ chunk table announces more chunks than the file has bytes",
        ));
    }
    if !laz_items_listed(&bytes) {
        return Err(Error::parse(
            path,
            "laszip record",
            "its LAZ description lists no compressed item: the file is damaged",
        ));
    }
    let offset = point_data_offset(&bytes);
    let mut reader = las::Reader::new(Cursor::new(bytes)).map_err(|e| bad("header", e))?;
    let header = reader.header();
    let count = header.number_of_points();
    let format = *header.point_format();
    let record = format.len() as u64;
    if !plausible(count, record, size, format.is_compressed) {
        return Err(Error::parse(
            path,
            "header",
            format!("it announces {count} points, more than its {size} bytes hold"),
        ));
    }
    if let Some(start) = offset.filter(|_| !format.is_compressed) {
        let end = start.saturating_add(count.saturating_mul(record));
        if end > size as u64 {
            return Err(Error::parse(
                path,
                "header",
                format!(
                    "its {count} points of {record} bytes start at byte {start} and end at byte \
                     {end}, past the file's end at byte {size}: the file is truncated or its \
                     header is wrong"
                ),
            ));
        }
    }
    reading.check_points(path, "header", count)?;
    let mut mesh = Mesh::default();
    let mut left_out = LeftOut::default();
    let mut seen = 0u64;
    let mut colors16: Vec<[u16; 3]> = Vec::new();
    let mut data = las::PointDataBuilder::new()
        .for_header(reader.header())
        .build();
    // Batches sized by what is left, so that a header's claims bound no allocation.
    let batch = BATCH.min(BATCH_BYTES / record.max(1)).max(1);
    loop {
        let left = count.saturating_sub(seen);
        if left == 0 {
            break;
        }
        let read = reader
            .fill_points(batch.min(left), &mut data)
            .map_err(|e| bad(&format!("point #{}", seen + 1), e))?;
        if read == 0 {
            break;
        }
        for point in data.points() {
            seen += 1;
            let at = format!("point #{seen}");
            let p = point.map_err(|e| bad(&at, e))?;
            let v: Vec3 = match point_f32("position", [p.x, p.y, p.z]) {
                Ok(v) => v,
                Err(m) => {
                    left_out.skip(reading, Error::parse(path, at, m))?;
                    continue;
                }
            };
            mesh.positions.push(v);
            if let Some(c) = p.color.filter(|_| format.has_color) {
                colors16.push([c.red, c.green, c.blue]);
            }
        }
    }
    mesh.left_out = left_out;
    if colors16.len() == mesh.positions.len() {
        let eight_bit = colors16.iter().flatten().all(|&c| c <= 255);
        let full = if eight_bit { 255.0 } else { 65535.0 };
        mesh.colors = Some(
            colors16
                .iter()
                .map(|c| c.map(|v| v as f32 / full))
                .collect(),
        );
    }
    Ok(mesh)
}
