//! `lobelight join`: the numbered frames that the shards of a sequence wrote (`render --views
//! FILE --shard K/N -o NAME_####.png`), in their order, as one video. Every index from 0 to the
//! last must be there: a missing frame is named, not skipped.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::video::VideoWriter;

/// The frames a numbered name stands for, by index: `NAME_####.png` (a run of `#`, any digits
/// in its place) or `NAME.png` (`NAME_NNNN.png`, as `scene::views::numbered` writes them).
pub fn frames(pattern: &Path) -> Result<Vec<PathBuf>> {
    let name = pattern
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| Error::Invalid(format!("{}: not a file name", pattern.display())))?;
    let (prefix, suffix) = match name.find('#') {
        Some(start) => {
            let run = name[start..].chars().take_while(|&c| c == '#').count();
            (name[..start].to_string(), name[start + run..].to_string())
        }
        None => match name.rfind('.') {
            Some(dot) => (format!("{}_", &name[..dot]), name[dot..].to_string()),
            None => (format!("{name}_"), String::new()),
        },
    };
    let dir = match pattern.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let entries = std::fs::read_dir(&dir).map_err(|e| Error::Io {
        path: dir.clone(),
        source: e,
    })?;
    let mut found: Vec<(usize, PathBuf)> = Vec::new();
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let Some(digits) = file
            .strip_prefix(&prefix)
            .and_then(|rest| rest.strip_suffix(&suffix))
        else {
            continue;
        };
        if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
            if let Ok(k) = digits.parse::<usize>() {
                found.push((k, entry.path()));
            }
        }
    }
    found.sort();
    if found.is_empty() {
        return Err(Error::Invalid(format!(
            "{}: no frame matches {prefix}N{suffix} in {}",
            pattern.display(),
            dir.display()
        )));
    }
    if let Some(w) = found.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(Error::Invalid(format!(
            "frame {} is there twice: {} and {}",
            w[0].0,
            w[0].1.display(),
            w[1].1.display()
        )));
    }
    for (expected, (k, _)) in found.iter().enumerate() {
        if *k != expected {
            return Err(Error::Invalid(format!(
                "frame {expected} of {prefix}N{suffix} is missing (found {} frames up to {}): \
                 a shard has not finished or failed",
                found.len(),
                found[found.len() - 1].0
            )));
        }
    }
    Ok(found.into_iter().map(|(_, p)| p).collect())
}

/// An 8-bit frame as RGBA8 pixels (red in the low byte) and its size.
fn read_frame(path: &Path) -> Result<(Vec<u32>, u32, u32)> {
    let image = image::open(path)
        .map_err(|e| Error::Invalid(format!("{}: not a readable frame: {e}", path.display())))?
        .to_rgba8();
    let (w, h) = image.dimensions();
    let pixels = image.pixels().map(|p| u32::from_le_bytes(p.0)).collect();
    Ok((pixels, w, h))
}

/// Joins the frames `pattern` names into `output` at `fps`; returns how many.
pub fn join(pattern: &Path, output: &Path, fps: f32, show: bool) -> Result<u64> {
    let frames = frames(pattern)?;
    let (first, w, h) = read_frame(&frames[0])?;
    let mut video = VideoWriter::create(output, w, h, fps)?;
    video.push(&first)?;
    let bar = crate::bake::Progress::new(show).bar_of(frames.len() as u64, "frames");
    for (k, path) in frames.iter().enumerate().skip(1) {
        let (pixels, fw, fh) = read_frame(path)?;
        if (fw, fh) != (w, h) {
            return Err(Error::Invalid(format!(
                "{}: {fw}×{fh}, where the first frame is {w}×{h}",
                path.display()
            )));
        }
        video.push(&pixels)?;
        bar.set_position(k as u64 + 1);
    }
    bar.finish_and_clear();
    video.finish()
}
