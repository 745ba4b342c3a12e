//! The GI worker thread. It owns its own `GpuContext`, `Scene` and `Renderer` (the renderer borrows
//! the other two, so all three are made inside the thread) and renders the jobs the UI sends. Jobs
//! queue in a channel; the worker takes the newest frame job and drops the stale ones, so the UI can
//! send one per camera change without falling behind. A reference job runs first and is stopped
//! between dispatches through its `Control`.

use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, Sender};
use std::thread::JoinHandle;
use std::time::Instant;

use anyhow::Result;
use glam::Vec3;

use crate::gi::pass::Pass;
use crate::gpu::GpuContext;
use crate::render::timed::FrameLoop;
use crate::render::{Cancelled, Control, Frame, RenderSettings, Renderer};
use crate::scene::{Camera, Scene};

/// Loads a scene by its spec, with the command line's added lights.
pub type Loader = Arc<dyn Fn(&str) -> Result<Scene> + Send + Sync>;

/// What the UI needs to know about the worker's scene.
#[derive(Clone, Debug)]
pub struct SceneInfo {
    pub spec: String,
    pub cameras: Vec<Camera>,
    pub default_camera: Camera,
    pub bounds: (Vec3, Vec3),
    pub triangles: usize,
    pub has_light: bool,
    /// The scene's punctual lights and emissive triangles (the panel edits the lights).
    pub lights: Vec<crate::scene::PunctualLight>,
    pub emissive_triangles: usize,
    pub adapter: String,
    /// The worker's adapter runs on the CPU (lavapipe): window frames share its cores.
    pub software: bool,
    /// The most pixels a GI frame may have on the worker's device (`render::max_pixels`).
    pub max_pixels: u64,
}

#[derive(Clone, Debug)]
pub struct FrameJob {
    pub id: u64,
    pub camera: Camera,
    pub settings: RenderSettings,
    /// Read back the SP clustering's nearest cluster per pixel.
    pub want_sp_ids: bool,
    /// Read back the counts the GPU keeps (`GpuFrame::counts`: the panel's counts section is open).
    pub want_counts: bool,
    /// A preview rendered while the camera moves (`preview_settings`).
    pub preview: bool,
    /// The split view's pinned B settings: rendered for the same camera right after this frame.
    pub b_settings: Option<RenderSettings>,
    /// Count the frame's lit pixels on the GPU (`Rendered::lit`; a scripted run's motion stats).
    pub count_lit: bool,
}

pub enum Job {
    Frame(FrameJob),
    /// Lights that move: the scene's punctual lights and the factor on its emissive materials
    /// (`Renderer::set_lights`), applied before the next frame.
    Lights(Vec<crate::scene::PunctualLight>, f32),
    /// The unclustered reference of this view; `settings.control` must be set.
    Reference(FrameJob),
}

/// A finished frame and what the views draw besides the images.
pub struct Rendered {
    pub job: FrameJob,
    /// The frame on the CPU; on the shared display path only its timings and counts (`GpuFrame::meta`:
    /// no images) unless the job needed pixels (SP ids, a reference).
    pub frame: Frame,
    /// On the shared display path: the frame's images where they were rendered, on the window's
    /// device.
    pub gpu: Option<crate::render::GpuFrame>,
    /// The split view's B frame on the GPU (shared display path).
    pub b_gpu: Option<crate::render::GpuFrame>,
    /// This frame's lit pixels counted on the GPU (read on request) and its pixels
    /// (`FrameJob::count_lit`).
    pub lit: Option<(crate::gi::sum::PendingSum, u32)>,
    /// Nearest SP cluster per pixel (u32::MAX: none), when asked for and SP clustering ran.
    pub sp_ids: Option<Vec<u32>>,
    /// VPL positions.
    pub vpls: Arc<Vec<Vec3>>,
    /// The light list's positions: VPL-cluster representatives, or the VPLs when not clustered.
    pub lights: Arc<Vec<Vec3>>,
    pub lights_clustered: bool,
    /// Wall-clock time of the render call, readbacks included.
    pub wall_ms: f64,
    /// The direct light accumulated at rest: (estimates, samples a pixel, GPU ms of the last one).
    pub refined: Option<(u32, u64, f64)>,
    /// GPU ms of (VPL trace, VPL clustering) when this frame traced new VPLs (the first frame, a
    /// light change, a new VPL count or seed).
    pub relit: Option<(f64, f64)>,
    /// The B settings' frame of the same camera (split view), when the job had them.
    pub b_frame: Option<Frame>,
    /// Under a time budget: the K_SP and K_VPL its controller chose for the next frame of this
    /// kind (`job.settings` holds the ones this frame ran with).
    pub budget_next: Option<(u32, u32)>,
    /// `exposure::auto_exposure` of the frame's radiance, computed here, off the UI thread (`None` on
    /// the shared display path, whose display pass reduces it on the GPU).
    pub auto_exposure: Option<f32>,
}

pub enum Reply {
    Loaded(Box<SceneInfo>),
    LoadFailed(String),
    Frame(Box<Rendered>),
    /// The direct light (emission + direct) of frame `id` averaged over `estimates` renders of it
    /// with different seeds (`samples` area samples a pixel in all), while the camera rests.
    Refined {
        id: u64,
        /// The mean on the CPU (split display path); `None`: refined in the frame's buffers on the
        /// GPU (shared).
        direct: Option<Vec<[f32; 3]>>,
        /// `exposure::auto_exposure` of the refined radiance (direct + the frame's indirect).
        auto_exposure: Option<f32>,
        estimates: u32,
        samples: u64,
        gpu_ms: f64,
    },
    Reference(Box<Rendered>),
    ReferenceCancelled,
    Failed(String),
}

pub struct Worker {
    tx: Option<Sender<Job>>,
    pub rx: Receiver<Reply>,
    handle: Option<JoinHandle<()>>,
}

pub enum Source {
    Loaded(Box<Scene>, String),
    Spec(String),
}

/// The window's device, shared with the GI worker (`--display-path shared`): the worker renders on
/// it and the window displays the frames' buffers where they are.
#[derive(Clone)]
pub struct SharedDevice {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
}

impl Worker {
    /// Starts a worker on `source`, on `shared` (the window's device) or a device of its own;
    /// `wake` is called after each reply.
    pub fn spawn(
        source: Source,
        loader: Loader,
        wake: Box<dyn Fn() + Send>,
        shared: Option<SharedDevice>,
    ) -> Worker {
        let (tx, jobs) = mpsc::channel::<Job>();
        let (reply_tx, rx) = mpsc::channel::<Reply>();
        let handle = std::thread::Builder::new()
            .name("gi-worker".into())
            .spawn(move || {
                let send = |r: Reply| {
                    let _ = reply_tx.send(r);
                    wake();
                };
                let (scene, spec) = match source {
                    Source::Loaded(s, spec) => (*s, spec),
                    Source::Spec(spec) => match loader(&spec) {
                        Ok(s) => (s, spec),
                        Err(e) => return send(Reply::LoadFailed(format!("{spec}: {e:#}"))),
                    },
                };
                if let Err(e) = serve(&scene, &spec, &jobs, &send, shared) {
                    send(Reply::LoadFailed(format!("{spec}: {e:#}")));
                }
            })
            .expect("spawning the GI worker thread");
        Worker {
            tx: Some(tx),
            rx,
            handle: Some(handle),
        }
    }

    pub fn send(&self, job: Job) {
        if let Some(tx) = &self.tx {
            let _ = tx.send(job);
        }
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        // Closing the channel ends the worker's loop after its current job.
        self.tx = None;
        if let Some(h) = self.handle.take() {
            // Detach: a frame in flight may take seconds on a software driver; never block the UI on it.
            drop(h);
        }
    }
}

/// The GI worker's nice value (the UI thread's is 0). Measured with `view builtin:conference --animate
/// --frames 60 --stats` on the 2-core VM (lavapipe), while moving: nice 10 gave an image latency p95
/// of 69 ms but previews of 3.4 s GPU time (the UI's frames starved them: 3 in 10 s); nice 0 gave
/// 309 ms previews but a p95 of 123 ms; nice 5 gave 82 ms and 0.9 s.
const WORKER_NICE: i32 = 5;

/// Lowers this thread's scheduling priority. On Linux `nice` is per thread and inherited by the
/// threads it creates, so a software driver's worker threads made for the GI device below run behind
/// the UI thread and its own driver threads: the window stays responsive while a frame renders.
fn lower_priority() {
    #[cfg(target_os = "linux")]
    // SAFETY: plain syscalls on the calling thread's id; failure only leaves the priority unchanged.
    unsafe {
        let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
        let _ = libc::setpriority(libc::PRIO_PROCESS, tid, WORKER_NICE);
    }
}

fn serve(
    scene: &Scene,
    spec: &str,
    jobs: &Receiver<Job>,
    send: &dyn Fn(Reply),
    shared: Option<SharedDevice>,
) -> Result<()> {
    lower_priority();
    let on_gpu = shared.is_some();
    let ctx = match shared {
        Some(d) => GpuContext::from_device(d.instance, d.adapter, d.device, d.queue)?,
        None => GpuContext::new_headless()?,
    };
    let mut renderer = Renderer::new(&ctx, scene)?;
    send(Reply::Loaded(Box::new(SceneInfo {
        spec: spec.to_string(),
        cameras: scene.cameras.clone(),
        default_camera: scene.default_camera(),
        bounds: scene.bounds(),
        triangles: scene.triangles.len(),
        has_light: scene.has_light(),
        lights: scene.lights.clone(),
        emissive_triangles: scene.emissive_triangle_count(),
        adapter: ctx.adapter_name.clone(),
        software: ctx.software,
        max_pixels: crate::render::max_pixels(&ctx, crate::render::PIXEL_BYTES),
    })));
    let mut cache = PointCache::default();
    // The frame loops of previews and of frames at rest, each stepping its own time budget.
    let mut loops = [FrameLoop::stepping_budget(), FrameLoop::stepping_budget()];
    let mut reference: Option<FrameJob> = None;
    let mut frame: Option<FrameJob> = None;
    let mut accumulation: Option<Accumulation> = None;
    let mut lights: Option<(Vec<crate::scene::PunctualLight>, f32)> = None;
    loop {
        if reference.is_none() && frame.is_none() {
            // Idle: refine the direct light of the frame at rest, or wait for a job.
            match accumulation
                .as_mut()
                .filter(|a| a.estimates < MAX_ESTIMATES)
            {
                Some(a) => match jobs.try_recv() {
                    Ok(j) => take(j, &mut reference, &mut frame, &mut lights),
                    Err(mpsc::TryRecvError::Empty) => {
                        let refined = crate::panic_guard::quietly(|| a.refine(&mut renderer))
                            .unwrap_or_else(|msg| Err(anyhow::anyhow!(msg)));
                        match refined {
                            Ok(reply) => send(reply),
                            Err(e) => {
                                accumulation = None;
                                send(Reply::Failed(format!("refining the direct light: {e:#}")));
                            }
                        }
                        continue;
                    }
                    Err(mpsc::TryRecvError::Disconnected) => return Ok(()),
                },
                None => match jobs.recv() {
                    Ok(j) => take(j, &mut reference, &mut frame, &mut lights),
                    Err(_) => return Ok(()),
                },
            }
        }
        accumulation = None;
        // Drop stale jobs: only the newest of each kind matters.
        loop {
            match jobs.try_recv() {
                Ok(j) => take(j, &mut reference, &mut frame, &mut lights),
                Err(mpsc::TryRecvError::Empty) => break,
                Err(mpsc::TryRecvError::Disconnected) => return Ok(()),
            }
        }
        if let Some((l, scale)) = lights.take()
            && let Err(msg) = crate::panic_guard::quietly(|| renderer.set_lights(&l, scale))
        {
            send(Reply::Failed(format!("changing the lights: {msg}")));
        }
        if let Some(job) = reference.take() {
            if job
                .settings
                .control
                .as_ref()
                .is_some_and(|c| c.is_cancelled())
            {
                send(Reply::ReferenceCancelled);
                continue;
            }
            let mut once = FrameLoop::default();
            // A reference is read back (once, when done: the error and the plot need its pixels).
            match render_guarded(&mut renderer, &mut cache, &mut once, job, false) {
                Ok(r) => send(Reply::Reference(Box::new(r))),
                Err(e) if e.is::<Cancelled>() => send(Reply::ReferenceCancelled),
                Err(e) => send(Reply::Failed(format!("reference: {e:#}"))),
            }
            continue;
        }
        if let Some(job) = frame.take() {
            if job.settings.cluster.target_ms.is_none() {
                // No budget: both controllers start anew when one is set again.
                loops = [FrameLoop::stepping_budget(), FrameLoop::stepping_budget()];
            }
            let frames = &mut loops[job.preview as usize];
            match render_guarded(&mut renderer, &mut cache, frames, job, on_gpu) {
                Ok(r) => {
                    if r.job.settings.cluster.temporal && !r.job.preview {
                        accumulation = Some(Accumulation::new(&r));
                    }
                    send(Reply::Frame(Box::new(r)))
                }
                Err(e) => send(Reply::Failed(format!("{e:#}"))),
            }
        }
    }
}

fn take(
    j: Job,
    reference: &mut Option<FrameJob>,
    frame: &mut Option<FrameJob>,
    lights: &mut Option<(Vec<crate::scene::PunctualLight>, f32)>,
) {
    match j {
        Job::Frame(f) => *frame = Some(f),
        Job::Lights(l, scale) => *lights = Some((l, scale)),
        Job::Reference(f) => {
            if let Some(old) = reference.replace(f)
                && let Some(c) = &old.settings.control
            {
                c.cancel();
            }
        }
    }
}

/// The sub-pixel offset of the `k`-th direct-light estimate at rest: the Halton (2, 3) point k,
/// centred, in (-0.5, 0.5)²; k = 0 (the frame itself) is the pixel centre.
pub fn subpixel_jitter(k: u32) -> [f32; 2] {
    fn radical_inverse(mut k: u32, base: u32) -> f32 {
        let (mut f, mut r) = (1.0f32, 0.0f32);
        while k > 0 {
            f /= base as f32;
            r += f * (k % base) as f32;
            k /= base;
        }
        r
    }
    if k == 0 {
        return [0.0, 0.0];
    }
    [radical_inverse(k, 2) - 0.5, radical_inverse(k, 3) - 0.5]
}

/// How many direct-light estimates a frame at rest accumulates (64 × 16 samples a pixel by default).
pub const MAX_ESTIMATES: u32 = 64;

/// The running mean of the direct light of the frame at rest (temporal reuse on): each idle turn of
/// the worker renders it again with another seed (`Renderer::direct_again`) and sends the mean. Any
/// job (a camera move, a settings change) ends it.
struct Accumulation {
    id: u64,
    settings: RenderSettings,
    target: Refining,
    estimates: u32,
}

/// Where the mean is kept.
enum Refining {
    /// On the CPU (split display path): the sum in f64, and the frame's indirect light (the
    /// exposure is of direct + indirect).
    Cpu {
        sum: Vec<[f64; 3]>,
        indirect: Vec<[f32; 3]>,
    },
    /// In the frame's own emission + direct buffer on the GPU (shared display path).
    Gpu(std::sync::Arc<crate::render::FrameBuffers>),
}

impl Accumulation {
    fn new(r: &Rendered) -> Self {
        Accumulation {
            id: r.job.id,
            settings: r.job.settings.clone(),
            target: match &r.gpu {
                Some(g) => Refining::Gpu(g.buffers.clone()),
                None => Refining::Cpu {
                    sum: r.frame.direct.iter().map(|p| p.map(|c| c as f64)).collect(),
                    indirect: r.frame.indirect.clone(),
                },
            },
            estimates: 1,
        }
    }

    fn refine(&mut self, renderer: &mut Renderer) -> Result<Reply> {
        let seed = self
            .settings
            .frame
            .seed
            .wrapping_add(self.estimates.wrapping_mul(0x9e37_79b9));
        // Anti-aliasing at rest: each estimate's primary rays through another sub-pixel offset.
        let jitter = subpixel_jitter(self.estimates);
        let samples = (self.estimates as u64 + 1) * self.settings.frame.direct_samples as u64;
        let (direct, auto_exposure, gpu_ms) = match &mut self.target {
            Refining::Gpu(frame) => {
                let n = self.estimates + 1;
                let ms = renderer.refine_direct(&self.settings, seed, Some(jitter), frame, n)?;
                (None, None, ms)
            }
            Refining::Cpu { sum, indirect } => {
                let (direct, gpu_ms) = renderer.direct_again(&self.settings, seed, Some(jitter))?;
                anyhow::ensure!(direct.len() == sum.len(), "the frame changed size");
                for (s, d) in sum.iter_mut().zip(&direct) {
                    for c in 0..3 {
                        s[c] += d[c] as f64;
                    }
                }
                let n = (self.estimates + 1) as f64;
                let direct: Vec<[f32; 3]> = sum.iter().map(|s| s.map(|c| (c / n) as f32)).collect();
                let radiance: Vec<[f32; 3]> = direct
                    .iter()
                    .zip(indirect.iter())
                    .map(|(a, b)| [0, 1, 2].map(|c| a[c] + b[c]))
                    .collect();
                let e = crate::exposure::auto_exposure(&radiance);
                (Some(direct), Some(e), gpu_ms)
            }
        };
        self.estimates += 1;
        Ok(Reply::Refined {
            id: self.id,
            direct,
            auto_exposure,
            estimates: self.estimates,
            samples,
            gpu_ms,
        })
    }
}

/// VPL and light positions, recomputed only when the resident sets change.
#[derive(Default)]
struct PointCache {
    vpl_key: Option<crate::gi::vpl_trace::VplKey>,
    vpls: Arc<Vec<Vec3>>,
    light_key: Option<crate::gi::vpl_cluster::LightKey>,
    lights: Arc<Vec<Vec3>>,
}

/// `render`, with a panic inside it (a wgpu validation error is one) turned into a one-line error
/// (nothing printed on stderr), so the UI hears of it instead of waiting for a reply that never
/// comes.
fn render_guarded(
    renderer: &mut Renderer,
    cache: &mut PointCache,
    frames: &mut FrameLoop,
    job: FrameJob,
    on_gpu: bool,
) -> Result<Rendered> {
    let (w, h) = (job.settings.frame.width, job.settings.frame.height);
    crate::panic_guard::quietly(|| render(renderer, cache, frames, job, on_gpu))
        .unwrap_or_else(|msg| Err(anyhow::anyhow!("the {w}x{h} GI frame failed: {msg}")))
}

/// A job's frame through `frames` (under a time budget, with its controller's K's: the job's
/// settings come back with them), its SP ids, its B frame, and the points the views draw. With
/// `on_gpu` (the shared display path) the frames stay on the GPU: read back only for the SP ids.
fn render(
    renderer: &mut Renderer,
    cache: &mut PointCache,
    frames: &mut FrameLoop,
    mut job: FrameJob,
    on_gpu: bool,
) -> Result<Rendered> {
    let t = Instant::now();
    let (frame, gpu, ran) = if on_gpu {
        let (g, ran) = frames.next_gpu(renderer, &job.camera, &job.settings)?;
        let frame = match (job.want_sp_ids, job.want_counts) {
            (true, _) => g.read(renderer.ctx)?,
            (false, true) => {
                let (meta, rays) = g.counts(&renderer.ctx.device, &renderer.ctx.queue)?;
                Frame {
                    shadow_rays: rays,
                    ..meta
                }
            }
            (false, false) => g.meta.clone(),
        };
        (frame, Some(g), ran)
    } else {
        let (f, ran) = frames.next(renderer, &job.camera, &job.settings)?;
        (f, None, ran)
    };
    job.settings = ran;
    let lit = match (&gpu, job.count_lit) {
        (Some(g), true) => {
            let lit = renderer.count_lit(&g.buffers);
            Some((lit, frame.width * frame.height))
        }
        _ => None,
    };
    // At the image's size (a render-scale clustering's labels, each image pixel its low-res one's).
    let sp_ids = match job.want_sp_ids {
        true => renderer.sp_labels(&frame)?,
        false => None,
    };
    // B after the SP ids are read (they are A's clustering's).
    let (b_frame, b_gpu) = match &job.b_settings {
        Some(b) if on_gpu => (None, Some(renderer.render_gpu(&job.camera, b)?)),
        Some(b) => (Some(renderer.render(&job.camera, b)?), None),
        None => (None, None),
    };
    let wall_ms = t.elapsed().as_secs_f64() * 1e3;
    let relit = match &renderer.vpl_set {
        Some(v) if cache.vpl_key != Some(v.key) => {
            Some((frame.ms(Pass::VplTrace), frame.ms(Pass::VplCluster)))
        }
        _ => None,
    };
    // In the caller's units (the renderer's are scaled by `geometry_scale`).
    let k = 1.0 / renderer.geometry_scale;
    let pos = |p: &[f32; 4]| (Vec3::new(p[0], p[1], p[2]).as_dvec3() * k).as_vec3();
    match &renderer.vpl_set {
        Some(v) if cache.vpl_key != Some(v.key) => {
            cache.vpl_key = Some(v.key);
            cache.vpls = Arc::new(v.set.vpls.iter().map(|v| pos(&v.pos)).collect());
        }
        None => {
            cache.vpl_key = None;
            cache.vpls = Arc::default();
        }
        _ => {}
    }
    match &renderer.lights {
        Some(l) if cache.light_key != Some(l.key) => {
            cache.light_key = Some(l.key);
            cache.lights = Arc::new(l.list.lights.iter().map(|v| pos(&v.pos)).collect());
        }
        None => {
            cache.light_key = None;
            cache.lights = Arc::default();
        }
        _ => {}
    }
    let lights_clustered = frame.vpl_clusters_used > 0;
    Ok(Rendered {
        auto_exposure: (!frame.radiance.is_empty())
            .then(|| crate::exposure::auto_exposure(&frame.radiance)),
        gpu,
        b_gpu,
        lit,
        job,
        frame,
        sp_ids,
        vpls: cache.vpls.clone(),
        lights: cache.lights.clone(),
        lights_clustered,
        wall_ms,
        refined: None,
        relit,
        b_frame,
        budget_next: frames.next_ks(),
    })
}

/// A fresh control for a reference job.
pub fn control() -> Arc<Control> {
    Arc::new(Control::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Halton (2, 3), centred: k = 1 is (0.5, 1/3) − 0.5, k = 2 (0.25, 2/3) − 0.5; every offset
    /// inside the pixel; the first 64 cover its four quadrants evenly.
    #[test]
    fn subpixel_jitter_is_halton() {
        assert_eq!(subpixel_jitter(0), [0.0, 0.0]);
        let close =
            |a: [f32; 2], b: [f32; 2]| (a[0] - b[0]).abs() < 1e-6 && (a[1] - b[1]).abs() < 1e-6;
        assert!(close(subpixel_jitter(1), [0.0, 1.0 / 3.0 - 0.5]));
        assert!(close(subpixel_jitter(2), [-0.25, 2.0 / 3.0 - 0.5]));
        let mut quadrants = [0; 4];
        for k in 1..=64 {
            let [x, y] = subpixel_jitter(k);
            assert!(x.abs() < 0.5 && y.abs() < 0.5);
            quadrants[(x >= 0.0) as usize * 2 + (y >= 0.0) as usize] += 1;
        }
        assert!(
            quadrants.iter().all(|&q| (12..=20).contains(&q)),
            "{quadrants:?}"
        );
    }
}
