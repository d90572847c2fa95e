//! A device's compute pipelines, by what they are made from (see
//! [`super::ComputePipeline`]): shared while in use, the most recently used idle ones
//! kept, and each made once even when several threads ask for it at the same time.

use super::Result;
use ash::vk;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};

/// The Vulkan objects of one compute pipeline, destroyed when the last user and the
/// device's cache have let go of them.
pub(crate) struct PipelineObjects {
    pub(crate) device: ash::Device,
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    pub(crate) set_layout: vk::DescriptorSetLayout,
}

impl Drop for PipelineObjects {
    fn drop(&mut self) {
        unsafe {
            self.device.destroy_pipeline(self.raw, None);
            self.device.destroy_pipeline_layout(self.layout, None);
            self.device
                .destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// Everything a compute pipeline's objects are made from.
#[derive(PartialEq, Eq)]
pub(crate) struct PipelineKey {
    /// (binding, descriptor type, count) of each binding.
    pub(crate) bindings: Vec<(u32, vk::DescriptorType, u32)>,
    pub(crate) push_constant_size: u32,
    pub(crate) specialization: Vec<u32>,
    pub(crate) spirv: Vec<u32>,
}

struct CacheEntry {
    key: PipelineKey,
    /// None while a thread is creating it.
    objects: Option<Arc<PipelineObjects>>,
    /// Unique per entry; raised each time the entry is used.
    last_used: u64,
}

#[derive(Default)]
struct CacheState {
    entries: Vec<CacheEntry>,
    clock: u64,
}

/// A device's compute pipelines, by what they are made from. Pipelines in use stay;
/// of those no [`super::ComputePipeline`] holds, the [`PipelineCache::IDLE_LIMIT`] most recently
/// used are kept for the next render. A thread asking for a pipeline another thread is
/// creating waits for it instead of compiling it a second time (a cold compile of a path
/// kernel takes 20–100 s on lavapipe). The device empties the cache before it is
/// destroyed.
#[derive(Default)]
pub(crate) struct PipelineCache {
    state: Mutex<CacheState>,
    created: Condvar,
}

impl PipelineCache {
    /// Idle pipelines kept: a process rendering every method of one scene, with and
    /// without AOVs, needs about this many variants.
    const IDLE_LIMIT: usize = 12;

    /// The state; a poisoned lock still holds a consistent state (nothing panics
    /// half-way through a change of it).
    fn lock(&self) -> MutexGuard<'_, CacheState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The pipeline made from `key`: the cached one, or the one `create` makes (without
    /// the lock held, so that other kernels compile meanwhile).
    pub(crate) fn get_or_create(
        &self,
        key: PipelineKey,
        create: impl FnOnce() -> Result<PipelineObjects>,
    ) -> Result<Arc<PipelineObjects>> {
        let mut state = self.lock();
        let id = loop {
            state.clock += 1;
            let clock = state.clock;
            match state.entries.iter_mut().find(|e| e.key == key) {
                Some(entry) => match &entry.objects {
                    Some(objects) => {
                        entry.last_used = clock;
                        return Ok(objects.clone());
                    }
                    None => state = self.created.wait(state).unwrap_or_else(|e| e.into_inner()),
                },
                None => {
                    state.entries.push(CacheEntry {
                        key,
                        objects: None,
                        last_used: clock,
                    });
                    break clock;
                }
            }
        };
        drop(state);
        // Whatever happens to `create` (an error, a panic), the placeholder goes and the
        // waiting threads wake up: they then try to create it themselves.
        let mut pending = Pending {
            cache: self,
            id,
            objects: None,
        };
        let objects = Arc::new(create()?);
        pending.objects = Some(objects.clone());
        Ok(objects)
    }

    /// Drop the least recently used idle pipelines beyond [`Self::IDLE_LIMIT`].
    fn evict(state: &mut CacheState) {
        loop {
            let idle = state.entries.iter().filter(|e| {
                e.objects
                    .as_ref()
                    .is_some_and(|o| Arc::strong_count(o) == 1)
            });
            if idle.clone().count() <= Self::IDLE_LIMIT {
                return;
            }
            let oldest = idle.map(|e| e.last_used).min().expect("an idle entry");
            state.entries.retain(|e| e.last_used != oldest);
        }
    }

    /// Destroy every pipeline (the device is about to be destroyed).
    pub(crate) fn clear(&self) {
        self.lock().entries.clear();
    }

    /// Pipelines held, in use or idle.
    pub(crate) fn len(&self) -> usize {
        self.lock()
            .entries
            .iter()
            .filter(|e| e.objects.is_some())
            .count()
    }
}

/// A placeholder entry of [`PipelineCache`]: filled in with `objects` when dropped, or
/// removed when `objects` is None; waiting threads are woken either way.
struct Pending<'a> {
    cache: &'a PipelineCache,
    id: u64,
    objects: Option<Arc<PipelineObjects>>,
}

impl Drop for Pending<'_> {
    fn drop(&mut self) {
        let mut state = self.cache.lock();
        let objects = self.objects.take();
        match objects {
            Some(objects) => {
                if let Some(e) = state.entries.iter_mut().find(|e| e.last_used == self.id) {
                    e.objects = Some(objects);
                }
                PipelineCache::evict(&mut state);
            }
            None => state.entries.retain(|e| e.last_used != self.id),
        }
        drop(state);
        self.cache.created.notify_all();
    }
}
