//! The CPU mirror's executor of `sequence`s: buffers are host words, and each dispatch runs
//! the stage's mirror at once, with the same bindings in the same order as its WGSL.

use std::cell::RefCell;
use std::rc::Rc;

use bytemuck::Pod;

use super::Mirror;
use super::bindings::{Bindings, CpuBuffer, view};
use crate::error::{Error, Result};
use crate::sequence::Executor;
use crate::shaders::{Pass, Stage};
use crate::shared::trace::Geometry;

/// Runs sequences on the CPU; tracing stages read `geometry` as their bind group 1.
#[derive(Default)]
pub struct CpuExecutor<'g> {
    pub geometry: Option<Geometry<'g>>,
}

impl<'g> CpuExecutor<'g> {
    /// An executor whose tracing stages walk `geometry`.
    pub fn tracing(geometry: Geometry<'g>) -> CpuExecutor<'g> {
        CpuExecutor {
            geometry: Some(geometry),
        }
    }
}

fn words_for(bytes: u64) -> usize {
    (bytes.div_ceil(4) as usize).max(1)
}

impl Executor for CpuExecutor<'_> {
    type Buffer = CpuBuffer;

    fn zeroed(&mut self, _label: &'static str, bytes: u64) -> Result<CpuBuffer> {
        Ok(Rc::new(RefCell::new(vec![0; words_for(bytes)])))
    }

    fn upload<T: Pod>(&mut self, _label: &'static str, data: &[T]) -> Result<CpuBuffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut words = vec![0u32; words_for(bytes.len().max(size_of::<T>()) as u64)];
        bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..bytes.len()].copy_from_slice(bytes);
        Ok(Rc::new(RefCell::new(words)))
    }

    fn uniform<T: Pod>(&mut self, label: &'static str, value: &T) -> Result<CpuBuffer> {
        self.upload(label, std::slice::from_ref(value))
    }

    fn dispatch(&mut self, pass: impl Into<Pass>, b: &[&CpuBuffer], groups: u32) -> Result<()> {
        run(pass.into(), b, None, groups)
    }

    fn dispatch_traced(
        &mut self,
        pass: impl Into<Pass>,
        b: &[&CpuBuffer],
        groups: u32,
    ) -> Result<()> {
        let pass = pass.into();
        let geo = self
            .geometry
            .ok_or_else(|| Error::Internal(format!("{pass}: no scene geometry to trace")))?;
        run(pass, b, Some(&geo), groups)
    }

    fn dispatch_variant(
        &mut self,
        stage: Stage,
        _defines: &[&'static str],
        _constants: &[(&'static str, f64)],
        b: &[&CpuBuffer],
        groups: u32,
    ) -> Result<()> {
        // The mirrors read the lobe count, family and the rest from the stage's parameters.
        run(stage.into(), b, None, groups)
    }

    fn copy(
        &mut self,
        src: &CpuBuffer,
        src_offset: u64,
        dst: &CpuBuffer,
        dst_offset: u64,
        bytes: u64,
    ) -> Result<()> {
        let data: Vec<u8> = {
            let src = src.borrow();
            let src: &[u8] = bytemuck::cast_slice(&src);
            let range = src_offset as usize..(src_offset + bytes) as usize;
            src.get(range)
                .ok_or_else(|| Error::Internal("copy past the end of a buffer".into()))?
                .to_vec()
        };
        let mut dst = dst.borrow_mut();
        let dst: &mut [u8] = bytemuck::cast_slice_mut(&mut dst);
        let range = dst_offset as usize..(dst_offset + bytes) as usize;
        dst.get_mut(range)
            .ok_or_else(|| Error::Internal("copy past the end of a buffer".into()))?
            .copy_from_slice(&data);
        Ok(())
    }

    fn read<T: Pod>(&mut self, buffer: &CpuBuffer, count: usize) -> Result<Vec<T>> {
        let words = buffer.borrow();
        let values = view::<T>(&words);
        values
            .get(..count)
            .map(<[T]>::to_vec)
            .ok_or_else(|| Error::Internal("readback past the end of a buffer".into()))
    }

    /// Each dispatch ran when it was made: nothing is left to wait for.
    fn finish(&mut self) -> Result<()> {
        Ok(())
    }
}

/// Runs `pass`'s mirror over `groups` workgroups with the dispatch's bindings, `geometry` as
/// a tracing stage's bind group 1.
fn run(pass: Pass, b: &[&CpuBuffer], geometry: Option<&Geometry>, groups: u32) -> Result<()> {
    let bindings = Bindings::new(pass.stage, b)?;
    match (super::mirror(pass), geometry) {
        (Some(Mirror::Plain(run)), _) => run(&bindings, groups),
        (Some(Mirror::Traced(run)), Some(geo)) => run(&bindings, geo, groups),
        (Some(Mirror::Traced(_)), None) => Err(bindings.internal("no scene geometry to trace")),
        (None, _) => {
            Err(bindings.internal("has no CPU executor entry (its mirror is called directly)"))
        }
    }
}
