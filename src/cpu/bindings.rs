//! A dispatch's bindings as a CPU mirror reads them: host words by binding index, in the order
//! the stage's WGSL declares them, viewed as the mirror's typed slices. Each mirror unpacks its
//! own bindings beside its code (its `dispatch`), and the executor runs it by its `Stage`.

use std::cell::{Ref, RefCell, RefMut};
use std::rc::Rc;

use bytemuck::Pod;

use crate::error::{Error, Result};
use crate::shaders::{Stage, stage_shape};

/// A buffer in host memory: 4-byte words, so every record type views it in place.
pub type CpuBuffer = Rc<RefCell<Vec<u32>>>;

/// One dispatch's bindings of group 0.
pub struct Bindings<'a> {
    stage: Stage,
    buffers: &'a [&'a CpuBuffer],
}

impl<'a> Bindings<'a> {
    /// `buffers` as `stage`'s bindings; refused where their count is not the one its WGSL
    /// declares in group 0.
    pub fn new(stage: Stage, buffers: &'a [&'a CpuBuffer]) -> Result<Bindings<'a>> {
        let declared = stage_shape(stage)?.bindings[0];
        if buffers.len() != declared as usize {
            return Err(Error::Internal(format!(
                "{stage}: {} bindings passed, its WGSL declares {declared}",
                buffers.len()
            )));
        }
        Ok(Bindings { stage, buffers })
    }

    /// The stage these are the bindings of.
    pub fn stage(&self) -> Stage {
        self.stage
    }

    /// Binding `i`, read-only.
    pub fn get(&self, i: usize) -> Result<Ref<'a, Vec<u32>>> {
        let stage = self.stage;
        self.buffers
            .get(i)
            .ok_or_else(|| Error::Internal(format!("{stage}: no binding {i}")))?
            .try_borrow()
            .map_err(|_| Error::Internal(format!("{stage}: binding {i} is also written")))
    }

    /// Binding `i`, written.
    pub fn get_mut(&self, i: usize) -> Result<RefMut<'a, Vec<u32>>> {
        let stage = self.stage;
        self.buffers
            .get(i)
            .ok_or_else(|| Error::Internal(format!("{stage}: no binding {i}")))?
            .try_borrow_mut()
            .map_err(|_| Error::Internal(format!("{stage}: binding {i} is bound twice")))
    }

    /// A uniform binding's value.
    pub fn param<T: Pod>(&self, i: usize) -> Result<T> {
        view::<T>(&self.get(i)?)
            .first()
            .copied()
            .ok_or_else(|| self.internal(&format!("binding {i} is too short")))
    }

    /// The first `N` words of a written binding (a stage's counters).
    pub fn counters<'b, const N: usize>(&self, words: &'b mut [u32]) -> Result<&'b mut [u32; N]> {
        words
            .get_mut(..N)
            .and_then(|c| c.try_into().ok())
            .ok_or_else(|| self.internal("counters too short"))
    }

    /// A broken invariant of this dispatch, named by its stage.
    pub fn internal(&self, what: &str) -> Error {
        Error::Internal(format!("{}: {what}", self.stage))
    }
}

/// The whole elements of `T` the words hold.
pub fn view<T: Pod>(words: &[u32]) -> &[T] {
    let bytes: &[u8] = bytemuck::cast_slice(words);
    bytemuck::cast_slice(&bytes[..bytes.len() / size_of::<T>() * size_of::<T>()])
}

/// The whole elements of `T` the words hold, written.
pub fn view_mut<T: Pod>(words: &mut [u32]) -> &mut [T] {
    let bytes: &mut [u8] = bytemuck::cast_slice_mut(words);
    let whole = bytes.len() / size_of::<T>() * size_of::<T>();
    bytemuck::cast_slice_mut(&mut bytes[..whole])
}
