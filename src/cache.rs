//! `--cache FILE`: the baked lobes on disk, keyed by a hash of everything the bake reads
//! (splats, materials, lights, grid and bake settings, program version) and nothing it does
//! not (camera, image size, tone mapping), so a new view loads them and any change re-bakes.

use std::path::Path;

use crate::em::{EmStats, LobeMap};
use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::types::{Lobe, SplatLight};

const MAGIC: &[u8; 8] = b"LOBELITE";
/// 2: lobes packed (`LobeMap::pack`), their count in the header's fourth field.
const VERSION: u32 = 2;
const HEADER: usize = 8 + 4 + 4 + 8 + 4 + 4;

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

/// The hash of what the bake depends on.
pub fn bake_key(scene: &Scene) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    h.write(env!("CARGO_PKG_VERSION").as_bytes());
    h.write(bytemuck::cast_slice(&scene.splats));
    h.write(bytemuck::cast_slice(&scene.materials));
    h.write(bytemuck::cast_slice(&scene.lights));
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
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Err(Miss::Missing)),
        Err(e) => return Err(io(path)(e)),
    };
    let bad = |why: &str| Error::Parse {
        path: path.to_path_buf(),
        at: "header".into(),
        message: format!("not a lobelight bake cache: {why}"),
    };
    if bytes.len() < HEADER || &bytes[..8] != MAGIC {
        return Err(bad("wrong magic bytes"));
    }
    let u32_at =
        |o: usize| u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let mut key_bytes = [0u8; 8];
    key_bytes.copy_from_slice(&bytes[16..24]);
    if u32_at(8) != VERSION || u64::from_le_bytes(key_bytes) != key {
        return Ok(Err(Miss::Stale));
    }
    let (lobe_count, per_splat, count) = (u32_at(12) as usize, u32_at(24), u32_at(28) as usize);
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
    Ok(Ok(map))
}

pub fn save(path: &Path, key: u64, map: &LobeMap) -> Result<()> {
    let mut bytes = Vec::with_capacity(HEADER + map.lobes.len() * size_of::<Lobe>());
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&VERSION.to_le_bytes());
    bytes.extend_from_slice(&(map.lobes.len() as u32).to_le_bytes());
    bytes.extend_from_slice(&key.to_le_bytes());
    bytes.extend_from_slice(&map.lobes_per_splat.to_le_bytes());
    bytes.extend_from_slice(&(map.light.len() as u32).to_le_bytes());
    bytes.extend_from_slice(bytemuck::cast_slice(&map.lobes));
    bytes.extend_from_slice(bytemuck::cast_slice(&map.light));
    std::fs::write(path, bytes).map_err(io(path))
}
