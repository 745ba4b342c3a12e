//! Resources a pass keeps from frame to frame, so that a frame at a steady size makes no buffer:
//! a uniform rewritten in place (`Uniform`), and a pool of buffer sets reused once their last user
//! let go (`Pool`).

use std::marker::PhantomData;
use std::sync::{Arc, Mutex, OnceLock};

use super::GpuContext;

/// A uniform buffer made the first time and rewritten after (`GpuContext::write_buffer`, counted as
/// uploaded). A write lands before the next submission and after the earlier ones, so a pass that
/// sets it and submits sees its own value.
pub struct Uniform<T> {
    label: &'static str,
    buffer: OnceLock<wgpu::Buffer>,
    _value: PhantomData<fn(T)>,
}

impl<T: bytemuck::Pod> Uniform<T> {
    pub const fn new(label: &'static str) -> Self {
        Uniform {
            label,
            buffer: OnceLock::new(),
            _value: PhantomData,
        }
    }

    /// The buffer holding `value`.
    pub fn set(&self, ctx: &GpuContext, value: &T) -> &wgpu::Buffer {
        if let Some(b) = self.buffer.get() {
            ctx.write_buffer(b, 0, bytemuck::bytes_of(value));
            return b;
        }
        self.buffer.get_or_init(|| ctx.uniform(self.label, value))
    }
}

impl<T: bytemuck::Pod> Default for Uniform<T> {
    /// Labelled by its type.
    fn default() -> Self {
        Self::new(std::any::type_name::<T>())
    }
}

/// Sets of GPU resources of a kind, keyed by what sizes them: `take` hands out one that nobody
/// holds any more (its `Arc` is the pool's only one) with the same key, else makes one. A frame's
/// results that the next frame reads (a warm start's clustering, the previous visibility) keep
/// their set held, so steady frames alternate between two.
pub struct Pool<K, V> {
    sets: Mutex<Vec<(K, Arc<V>)>>,
}

impl<K, V> Default for Pool<K, V> {
    fn default() -> Self {
        Pool {
            sets: Mutex::new(Vec::new()),
        }
    }
}

impl<K: PartialEq + Clone, V> Pool<K, V> {
    /// A free set of `key` (`reused`: true) or a new one from `make` (kept in the pool); sets of
    /// other keys that nobody holds are dropped.
    pub fn take(&self, key: &K, make: impl FnOnce() -> V) -> (Arc<V>, bool) {
        let mut sets = self.sets.lock().unwrap_or_else(|e| e.into_inner());
        sets.retain(|(k, v)| k == key || Arc::strong_count(v) > 1);
        if let Some((_, v)) = sets
            .iter()
            .find(|(k, v)| k == key && Arc::strong_count(v) == 1)
        {
            return (v.clone(), true);
        }
        let v = Arc::new(make());
        sets.push((key.clone(), v.clone()));
        (v, false)
    }

    /// Sets made and still kept (held or free).
    pub fn len(&self) -> usize {
        self.sets.lock().unwrap_or_else(|e| e.into_inner()).len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A set comes back once its holder drops it; a held one is not handed out twice; a key
    /// change drops the free sets of the old key.
    #[test]
    fn pool_reuses_free_sets_of_the_same_key() {
        let pool: Pool<u32, u32> = Pool::default();
        let mut made = 0;
        let (a, reused) = pool.take(&1, || {
            made += 1;
            10
        });
        assert!(!reused);
        let (b, reused) = pool.take(&1, || {
            made += 1;
            20
        });
        assert!(!reused && *b == 20);
        drop(a);
        let (c, reused) = pool.take(&1, || unreachable!("set 10 is free"));
        assert!(reused && *c == 10);
        drop((b, c));
        assert_eq!(pool.len(), 2);
        let (_d, reused) = pool.take(&2, || 30);
        assert!(!reused);
        assert_eq!(pool.len(), 1, "the free sets of key 1 are dropped");
        assert_eq!(made, 2);
    }
}
