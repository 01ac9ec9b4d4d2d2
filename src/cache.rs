//! `--cache FILE`: the baked lobes on disk, keyed by a hash of everything the bake reads
//! (splats, materials, lights, grid and bake settings, program version) and nothing it does
//! not (camera, image size, tone mapping), so a new view loads them and any change re-bakes.
//!
//! Layout (little-endian): the magic bytes, a 64-bit FNV-1a checksum of everything after it,
//! then the format version, the lobe count, the key, lobes per splat, the splat count, the
//! packed lobes and the splats' light. A file whose checksum does not match (a byte flipped
//! on disk or in a copy, a truncated write) is an error naming the file, never a silent image.

use std::path::Path;

use crate::em::{EmStats, LobeMap};
use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::shared::lobes::MAX_LOBES;
use crate::types::{Lobe, SplatLight};

const MAGIC: &[u8; 8] = b"LOBELITE";
/// 2: lobes packed (`LobeMap::pack`), their count in the header; 3: a checksum after the magic.
const VERSION: u32 = 3;
/// The version of the files before the checksum, whose version field sits where the checksum
/// now begins: such a file is stale, not corrupt.
const VERSION_UNCHECKED: u32 = 2;
const HEADER: usize = 8 + 8 + 4 + 4 + 8 + 4 + 4;

/// 64-bit FNV-1a: small, and stable across platforms and compiler versions (the standard
/// library's hasher promises neither).
struct Fnv(u64);

impl Fnv {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
}

/// Raised whenever the bake's result changes for the same scene and settings (an estimator
/// mended, a stage added), so that caches baked before are stale rather than silently loaded:
/// 1: photons end at the lights they meet; 2: a box's and a quad's disks end at its edges;
/// 3: the splats' irradiance from photon deposits; 4: the covered share on every path; 5:
/// shared fits; 6: the photons' estimate smoothed where the light is smooth; 7: smoothing
/// chosen once a coverage group; 8: the deposits summed once a coverage group.
const BAKE_REVISION: u32 = 8;

/// The hash of what the bake depends on.
pub fn bake_key(scene: &Scene) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    h.write(env!("CARGO_PKG_VERSION").as_bytes());
    h.write(&BAKE_REVISION.to_le_bytes());
    h.write(bytemuck::cast_slice(&scene.splats));
    h.write(bytemuck::cast_slice(&scene.materials));
    h.write(bytemuck::cast_slice(&scene.lights));
    // A sky's map (the header alone, unhashed, where the scene has none: keys stay as they were).
    if scene.sky.entries().len() > 1 {
        h.write(bytemuck::cast_slice(scene.sky.entries()));
    }
    h.write(format!("{:?}", scene.grid).as_bytes());
    h.write(format!("{:?}", scene.bake).as_bytes());
    h.write(&scene.search_radius().to_le_bytes());
    h.0
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Why a cache file could not be used.
#[derive(Debug, PartialEq, Eq)]
pub enum Miss {
    Missing,
    Stale,
}

/// The lobes in `path` if it was written for `key`; a file that is not a cache is an error.
pub fn load(path: &Path, key: u64, splats: usize) -> Result<std::result::Result<LobeMap, Miss>> {
    let bad = |why: &str| Error::Parse {
        path: path.to_path_buf(),
        at: "header".into(),
        message: format!("not a lobelight bake cache: {why}"),
    };
    // What the file may hold is bounded by the scene before a byte is read: a file larger
    // than any cache of this scene is some other file, never read into memory.
    let size = match std::fs::metadata(path) {
        Ok(m) if !m.is_file() => return Err(bad("it is not a regular file")),
        Ok(m) => m.len(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Err(Miss::Missing)),
        Err(e) => return Err(io(path)(e)),
    };
    let per_splat = size_of::<SplatLight>() + MAX_LOBES as usize * size_of::<Lobe>();
    let most = (HEADER + splats.saturating_mul(per_splat)) as u64;
    if size > most {
        return Err(bad(&format!(
            "its {size} bytes are more than a bake cache of this scene's {splats} splats holds \
             ({most} at most); name another --cache file"
        )));
    }
    let bytes = std::fs::read(path).map_err(io(path))?;
    if bytes.len() < 12 || &bytes[..8] != MAGIC {
        return Err(bad("wrong magic bytes"));
    }
    let u32_at =
        |o: usize| u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let u64_at = |o: usize| {
        let mut b = [0u8; 8];
        b.copy_from_slice(&bytes[o..o + 8]);
        u64::from_le_bytes(b)
    };
    // A file of the format before the checksum: its size matches its own header.
    let unchecked_len = |b: &[u8]| {
        let payload = u32_at(12) as u64 * size_of::<Lobe>() as u64
            + u32_at(28) as u64 * size_of::<SplatLight>() as u64;
        b.len() >= 32 && b.len() as u64 == 32 + payload
    };
    if u32_at(8) == VERSION_UNCHECKED && unchecked_len(&bytes) {
        return Ok(Err(Miss::Stale));
    }
    if bytes.len() < HEADER {
        return Err(bad("it is shorter than its header"));
    }
    if u64_at(8) != checksum(&bytes[16..]) {
        return Err(bad(
            "its checksum does not match its contents (the file is damaged); delete it to bake \
             again",
        ));
    }
    if u32_at(16) != VERSION || u64_at(24) != key {
        return Ok(Err(Miss::Stale));
    }
    let (lobe_count, per_splat, count) = (u32_at(20) as usize, u32_at(32), u32_at(36) as usize);
    let lobe_bytes = lobe_count * size_of::<Lobe>();
    let light_bytes = count * size_of::<SplatLight>();
    if count != splats || bytes.len() != HEADER + lobe_bytes + light_bytes {
        return Err(bad("its size does not match its header"));
    }
    let (lobes, light) = bytes[HEADER..].split_at(lobe_bytes);
    let map = LobeMap {
        lobes_per_splat: per_splat,
        lobes: bytemuck::pod_collect_to_vec(lobes),
        light: bytemuck::pod_collect_to_vec(light),
        stats: EmStats::default(),
    };
    map.check_packed().map_err(|why| bad(&why))?;
    map.check_values().map_err(|why| {
        Error::parse(
            path,
            "values",
            format!("{why}: the file is damaged; delete it to bake again"),
        )
    })?;
    Ok(Ok(map))
}

/// FNV-1a over `bytes`: any one changed byte changes it (each step is invertible).
fn checksum(bytes: &[u8]) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    h.write(bytes);
    h.0
}

pub fn save(path: &Path, key: u64, map: &LobeMap) -> Result<()> {
    let mut bytes = Vec::with_capacity(HEADER + map.lobes.len() * size_of::<Lobe>());
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&[0u8; 8]);
    bytes.extend_from_slice(&VERSION.to_le_bytes());
    bytes.extend_from_slice(&(map.lobes.len() as u32).to_le_bytes());
    bytes.extend_from_slice(&key.to_le_bytes());
    bytes.extend_from_slice(&map.lobes_per_splat.to_le_bytes());
    bytes.extend_from_slice(&(map.light.len() as u32).to_le_bytes());
    bytes.extend_from_slice(bytemuck::cast_slice(&map.lobes));
    bytes.extend_from_slice(bytemuck::cast_slice(&map.light));
    let sum = checksum(&bytes[16..]);
    bytes[8..16].copy_from_slice(&sum.to_le_bytes());
    std::fs::write(path, bytes).map_err(io(path))
}
