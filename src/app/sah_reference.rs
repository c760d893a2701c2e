//! The quality anchor shown next to the current tree's SAH: the CPU full-sweep SAH builder's cost
//! for the same scene and leaf size, computed in a background thread (it takes seconds on large
//! scenes) once per (scene, max leaf size). One computation runs at a time; a request made while
//! one runs starts when it ends.

use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::sync::Arc;

use crate::bvh::{build_sweep_sah, sah_cost, SahParams};
use crate::scene::Scene;

/// What the reference is computed for: a scene generation and a maximum leaf size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReferenceKey {
    pub scene_id: u64,
    pub max_leaf_size: u32,
}

/// State of the reference for the current key.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ReferenceState {
    Computing,
    Ready(f32),
    Failed,
}

struct Job {
    key: ReferenceKey,
    scene: Arc<Scene>,
    params: SahParams,
}

#[derive(Default)]
pub struct SahReference {
    wanted: Option<ReferenceKey>,
    pending: Option<Job>,
    running: Option<(ReferenceKey, Receiver<f32>)>,
    done: Option<(ReferenceKey, ReferenceState)>,
}

impl SahReference {
    /// Asks for the reference of `scene` under `params`; does nothing if it is already known or
    /// on its way.
    pub fn request(&mut self, key: ReferenceKey, scene: &Arc<Scene>, params: SahParams) {
        if self.wanted == Some(key) {
            return;
        }
        self.wanted = Some(key);
        self.pending = Some(Job {
            key,
            scene: Arc::clone(scene),
            params,
        });
        self.poll();
    }

    /// Collects a finished computation and starts the pending one; call once per frame.
    pub fn poll(&mut self) {
        if let Some((key, rx)) = &self.running {
            let finished = match rx.try_recv() {
                Ok(cost) => Some(ReferenceState::Ready(cost)),
                Err(TryRecvError::Empty) => None,
                Err(TryRecvError::Disconnected) => Some(ReferenceState::Failed),
            };
            if let Some(state) = finished {
                self.done = Some((*key, state));
                self.running = None;
            }
        }
        if self.running.is_some() {
            return;
        }
        let Some(job) = self.pending.take() else {
            return;
        };
        if self.done.is_some_and(|(key, _)| key == job.key) {
            return;
        }
        let (tx, rx) = mpsc::channel();
        let key = job.key;
        let spawned = std::thread::Builder::new()
            .name("sah-reference".into())
            .spawn(move || {
                let bvh = build_sweep_sah(&job.scene.triangles, &job.params);
                // The receiver may be gone when the viewer closed; nothing to do then.
                let _ = tx.send(sah_cost(&bvh, &job.params));
            });
        match spawned {
            Ok(_) => self.running = Some((key, rx)),
            Err(e) => {
                log::warn!("cannot start the SAH reference thread: {e}");
                self.done = Some((key, ReferenceState::Failed));
            }
        }
    }

    /// The reference for the most recently requested key.
    pub fn state(&self) -> ReferenceState {
        match self.done {
            Some((key, state)) if Some(key) == self.wanted => state,
            _ => ReferenceState::Computing,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::cornell_box;

    #[test]
    fn computes_the_sweep_cost_in_the_background() {
        let scene = Arc::new(cornell_box());
        let params = SahParams::default();
        let key = ReferenceKey {
            scene_id: 1,
            max_leaf_size: params.max_leaf_size,
        };
        let mut reference = SahReference::default();
        reference.request(key, &scene, params);
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
        while reference.state() == ReferenceState::Computing {
            assert!(
                std::time::Instant::now() < deadline,
                "reference never finished"
            );
            std::thread::sleep(std::time::Duration::from_millis(5));
            reference.poll();
        }
        let expected = sah_cost(&build_sweep_sah(&scene.triangles, &params), &params);
        assert_eq!(reference.state(), ReferenceState::Ready(expected));
        // A new key reads "computing" until its own result arrives.
        let other = ReferenceKey {
            max_leaf_size: 2,
            ..key
        };
        reference.request(
            other,
            &scene,
            SahParams {
                max_leaf_size: 2,
                ..params
            },
        );
        assert_eq!(reference.state(), ReferenceState::Computing);
    }
}
