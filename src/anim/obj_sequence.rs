//! OBJ sequences: a folder of frame OBJs with identical topology (the same triangles in the same
//! order with the same materials; e.g. the reference frames of the BART scenes), loaded once and
//! interpolated linearly between consecutive frames. The interpolation runs on the CPU and the
//! result is uploaded with `queue.write_buffer` each frame (like BART scenes: a CPU evaluation +
//! upload; the BVH build stays on the GPU). Keeping the frames on the CPU keeps GPU memory at one
//! frame however long the sequence is.
//!
//! Frame times: when every file name ends in a number (`frame_0000.obj`, `frame_0400.obj`) those
//! numbers are the frame times, one animation frame per unit (so the BART frames 0 and 400 span
//! 401 frames); otherwise the files are taken in name order, one time unit apart, with 30 frames
//! per unit.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;

use super::{check_triangle_count, AnimateStage, Animation, TimeRange};
use crate::device::Geometry;
use crate::gpu::{Recorder, StageTime};
use crate::scene::{load_obj, Camera, Material, Triangle};
use crate::{Error, Result};

/// Frames per time unit of a sequence whose file names carry no frame numbers.
const FRAMES_PER_UNIT_UNNUMBERED: u32 = 30;

/// Frame OBJs interpolated over time.
pub struct ObjSequence {
    name: String,
    /// Keyframe times, strictly increasing, one per entry of `frames`.
    times: Vec<f32>,
    frames: Vec<Vec<Triangle>>,
    range: TimeRange,
    materials: Vec<Material>,
    camera: Camera,
    sky: Vec3,
    scratch: Vec<Triangle>,
}

/// The number at the end of a file stem (`frame_0400` → 400).
fn trailing_number(path: &Path) -> Option<u32> {
    let stem = path.file_stem()?.to_str()?;
    let digits = stem.len() - stem.trim_end_matches(|c: char| c.is_ascii_digit()).len();
    stem[stem.len() - digits..].parse().ok()
}

/// The `.obj` files of `dir` with their times, in time order.
fn frame_files(dir: &Path) -> Result<(Vec<PathBuf>, Vec<f32>, u32)> {
    let io_error = |source| Error::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io_error)?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")))
        .collect();
    if files.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "{}: no .obj files (an OBJ sequence is a folder of frame OBJs)",
            dir.display()
        )));
    }
    files.sort();
    let numbers: Option<Vec<u32>> = files.iter().map(|p| trailing_number(p)).collect();
    if let Some(mut numbered) = numbers.map(|n| files.iter().cloned().zip(n).collect::<Vec<_>>()) {
        numbered.sort_by_key(|&(_, n)| n);
        if numbered.windows(2).all(|w| w[0].1 < w[1].1) {
            let span = numbered[numbered.len() - 1].1 - numbered[0].1;
            let times = numbered.iter().map(|&(_, n)| n as f32).collect();
            let files = numbered.into_iter().map(|(p, _)| p).collect();
            return Ok((files, times, span + 1));
        }
    }
    let times = (0..files.len()).map(|i| i as f32).collect();
    let frames = (files.len() as u32 - 1) * FRAMES_PER_UNIT_UNNUMBERED + 1;
    Ok((files, times, frames))
}

impl ObjSequence {
    /// Loads every `.obj` file of `dir` as one frame. Errors: a folder that cannot be read
    /// (`Error::Io`), one without OBJ files, a frame whose topology (triangle count or any
    /// triangle's material) differs from the first frame's (`Error::InvalidArgument`, naming the
    /// file), and any OBJ error of a frame.
    pub fn load(name: &str, dir: &Path) -> Result<Self> {
        let (files, times, frame_count) = frame_files(dir)?;
        let first = load_obj(&files[0])?;
        if first.triangles.is_empty() {
            return Err(Error::EmptyScene(files[0].display().to_string()));
        }
        let mut frames = vec![first.triangles.clone()];
        for file in &files[1..] {
            let scene = load_obj(file)?;
            let same_topology = scene.triangles.len() == first.triangles.len()
                && scene
                    .triangles
                    .iter()
                    .zip(&first.triangles)
                    .all(|(a, b)| a.material == b.material);
            if !same_topology {
                return Err(Error::InvalidArgument(format!(
                    "{}: its topology differs from {} ({} vs {} triangles, or other materials): \
                     the frames of an OBJ sequence need the same triangles in the same order",
                    file.display(),
                    files[0].display(),
                    scene.triangles.len(),
                    first.triangles.len()
                )));
            }
            frames.push(scene.triangles);
        }
        let range = TimeRange::new(times[0], times[times.len() - 1], frame_count);
        Ok(Self {
            name: name.to_owned(),
            times,
            frames,
            range,
            materials: first.materials,
            camera: first.camera,
            sky: first.sky,
            scratch: Vec::new(),
        })
    }

    /// The same sequence seen from `camera` (instead of the framing of the first frame).
    pub fn with_camera(mut self, camera: Camera) -> Self {
        self.camera = camera;
        self
    }
}

impl Animation for ObjSequence {
    fn name(&self) -> &str {
        &self.name
    }

    fn time_range(&self) -> TimeRange {
        self.range
    }

    fn triangle_count(&self) -> usize {
        self.frames[0].len()
    }

    fn materials(&self) -> &[Material] {
        &self.materials
    }

    fn camera(&self, _t: f32) -> Camera {
        self.camera
    }

    fn sky(&self) -> Vec3 {
        self.sky
    }

    fn stage(&self) -> AnimateStage {
        AnimateStage::CpuUpload
    }

    /// Linear interpolation between the two frames around `t` (clamped to the first and last).
    fn evaluate(&self, t: f32, out: &mut Vec<Triangle>) {
        out.clear();
        let next = self.times.partition_point(|&k| k <= t);
        if next == 0 || next == self.times.len() {
            let i = next.saturating_sub(1);
            out.extend_from_slice(&self.frames[i]);
            return;
        }
        let (t0, t1) = (self.times[next - 1], self.times[next]);
        let s = (t - t0) / (t1 - t0);
        let lerp = |a: [f32; 3], b: [f32; 3]| Vec3::from(a).lerp(Vec3::from(b), s);
        out.extend(
            self.frames[next - 1]
                .iter()
                .zip(&self.frames[next])
                .map(|(a, b)| {
                    Triangle::new(
                        lerp(a.v0, b.v0),
                        lerp(a.v1, b.v1),
                        lerp(a.v2, b.v2),
                        a.material,
                    )
                }),
        );
    }

    fn animate(
        &mut self,
        rec: &mut Recorder<'_>,
        t: f32,
        geometry: &Geometry,
    ) -> Result<Option<StageTime>> {
        check_triangle_count(self, geometry)?;
        let start = Instant::now();
        let mut scratch = std::mem::take(&mut self.scratch);
        self.evaluate(t, &mut scratch);
        let written = geometry.write_triangles(rec.ctx, &scratch);
        self.scratch = scratch;
        written?;
        Ok(Some(StageTime::cpu(
            "animate",
            start.elapsed().as_secs_f64() * 1e3,
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) {
        std::fs::write(dir.join(name), text).unwrap();
    }

    fn temp_dir(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("treelet-objseq-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn numbered_frames_interpolate_linearly() {
        let dir = temp_dir("lerp");
        write(&dir, "f_0010.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        write(&dir, "f_0000.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        write(&dir, "f_0020.obj", "v 2 0 0\nv 3 0 0\nv 2 1 0\nf 1 2 3\n");
        let seq = ObjSequence::load("seq", &dir).unwrap();
        assert_eq!(seq.time_range(), TimeRange::new(0.0, 20.0, 21));
        let mut out = Vec::new();
        seq.evaluate(15.0, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].v0, [1.0, 0.0, 0.0]);
        seq.evaluate(99.0, &mut out);
        assert_eq!(out[0].v0, [2.0, 0.0, 0.0]);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn differing_topology_names_the_file() {
        let dir = temp_dir("topo");
        write(&dir, "a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        write(
            &dir,
            "b.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n",
        );
        let e = ObjSequence::load("seq", &dir)
            .err()
            .expect("topology differs")
            .to_string();
        assert!(e.contains("b.obj") && e.contains("topology"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
