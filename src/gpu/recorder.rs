//! A recording of GPU work, executed later: a command encoder, the parameter slab its dispatches
//! upload from, and optionally a timer whose timestamped passes it opens. Stages append compute
//! passes (`Recorder::pass`) and buffer commands (`Recorder::encoder`) and never submit or wait;
//! whoever owns the recording submits it once, with everything a frame needs.

use bytemuck::Pod;

use super::{GpuContext, GpuTimer, Grid, ItemCount, Items, Kernel, ParamSlab};

pub struct Recorder<'a> {
    pub ctx: &'a GpuContext,
    encoder: wgpu::CommandEncoder,
    params: &'a mut ParamSlab,
    timer: Option<&'a mut GpuTimer>,
    /// The timer's queries were resolved (no passes may follow).
    resolved: bool,
    /// Put before the label of every pass opened from now on.
    prefix: &'static str,
}

impl<'a> Recorder<'a> {
    /// Starts a recording; `params` is reset (its previous recording must have been submitted).
    pub fn new(
        ctx: &'a GpuContext,
        params: &'a mut ParamSlab,
        timer: Option<&'a mut GpuTimer>,
    ) -> Self {
        params.reset();
        Self {
            ctx,
            encoder: ctx.device.create_command_encoder(&Default::default()),
            params,
            timer,
            resolved: false,
            prefix: "",
        }
    }

    /// Labels the passes opened from now on `prefix` + label (e.g. to tell a second tree's build
    /// stages from the first's in one recording).
    pub fn set_pass_prefix(&mut self, prefix: &'static str) {
        self.prefix = prefix;
    }

    /// The recording's timer, if it has one.
    pub fn timer_mut(&mut self) -> Option<&mut GpuTimer> {
        self.timer.as_deref_mut()
    }

    /// For buffer commands between passes (clears, copies).
    pub fn encoder(&mut self) -> &mut wgpu::CommandEncoder {
        &mut self.encoder
    }

    /// Opens a compute pass named `label`, timestamped when the recording has a timer (when the
    /// timer profiles dispatches, each dispatch gets a timed pass of its own instead).
    pub fn pass(&mut self, label: &str) -> Pass<'_> {
        debug_assert!(
            !self.resolved,
            "pass '{label}' after the timer was resolved"
        );
        let mut pass = Pass {
            pass: None,
            label: format!("{}{label}", self.prefix),
            encoder: &mut self.encoder,
            timer: self.timer.as_deref_mut(),
            ctx: self.ctx,
            params: self.params,
        };
        if !pass.per_dispatch() {
            pass.begin(None);
        }
        pass
    }

    /// Submits what is recorded so far and goes on in a new command encoder: for the few steps
    /// that must read a result back before they can record on (tests, and the pre-split
    /// reference count). Off the per-frame path.
    pub fn flush(&mut self) {
        self.params.upload(&self.ctx.queue);
        let encoder = std::mem::replace(
            &mut self.encoder,
            self.ctx.device.create_command_encoder(&Default::default()),
        );
        self.ctx.queue.submit([encoder.finish()]);
    }

    /// Resolves the timer's queries now, so that the recording can copy them (`GpuTimer::
    /// resolved_buffer`); no timestamped pass may follow.
    pub fn resolve_timer(&mut self) {
        if let Some(timer) = self.timer.as_deref() {
            if !self.resolved {
                timer.resolve(&mut self.encoder);
            }
        }
        self.resolved = true;
    }

    /// Uploads the parameters and resolves the timer; the command buffer to submit.
    pub fn finish(mut self) -> wgpu::CommandBuffer {
        self.params.upload(&self.ctx.queue);
        self.resolve_timer();
        self.encoder.finish()
    }

    /// `finish` and submit.
    pub fn submit(self) {
        let ctx = self.ctx;
        ctx.queue.submit([self.finish()]);
    }
}

/// A compute pass of a recording (or, when its timer profiles dispatches, one per dispatch).
pub struct Pass<'r> {
    /// The open wgpu pass (None before the first dispatch when dispatches are timed one by one).
    pass: Option<wgpu::ComputePass<'static>>,
    label: String,
    encoder: &'r mut wgpu::CommandEncoder,
    timer: Option<&'r mut GpuTimer>,
    ctx: &'r GpuContext,
    params: &'r mut ParamSlab,
}

impl<'r> Pass<'r> {
    pub fn ctx(&self) -> &'r GpuContext {
        self.ctx
    }

    fn per_dispatch(&self) -> bool {
        self.timer.as_deref().is_some_and(GpuTimer::per_dispatch)
    }

    /// Ends the open wgpu pass, if any, and opens the next one (timed; for one dispatch of
    /// `kernel` when dispatches are timed one by one).
    fn begin(&mut self, kernel: Option<&'static str>) {
        drop(self.pass.take());
        let timestamp_writes = self
            .timer
            .as_deref_mut()
            .and_then(|t| t.pass(&self.label, kernel));
        self.pass = Some(
            self.encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(&self.label),
                    timestamp_writes,
                })
                .forget_lifetime(),
        );
    }

    /// The wgpu pass a dispatch of `kernel` goes into.
    fn pass_for(&mut self, kernel: &'static str) -> &mut wgpu::ComputePass<'static> {
        if self.per_dispatch() {
            self.begin(Some(kernel));
        }
        self.pass.as_mut().expect("a pass is open")
    }

    /// Dispatches a kernel of one invocation per item over `count` items.
    pub fn dispatch_items(
        &mut self,
        kernel: &Kernel<Items>,
        count: u32,
        buffers: &[&wgpu::Buffer],
    ) {
        let grid = kernel.grid(self.ctx, count);
        self.dispatch(kernel, grid, &Items::new(count, grid), buffers);
    }

    /// Dispatches a kernel of one invocation per item over `count`'s capacity, with `buffers` and
    /// then the count's limit (the kernel's last binding, `count_limit`; see `ItemCount`).
    pub fn dispatch_counted(
        &mut self,
        kernel: &Kernel<Items>,
        count: ItemCount<'_>,
        buffers: &[&wgpu::Buffer],
    ) {
        let grid = kernel.grid(self.ctx, count.capacity());
        let mut bound = buffers.to_vec();
        bound.push(count.limit(self.ctx));
        self.dispatch(kernel, grid, &Items::new(count.capacity(), grid), &bound);
    }

    /// Dispatches `kernel` over `grid` with `params` and `buffers` bound to bindings 1, 2, ... in
    /// declaration order.
    pub fn dispatch<P: Pod>(
        &mut self,
        kernel: &Kernel<P>,
        grid: Grid,
        params: &P,
        buffers: &[&wgpu::Buffer],
    ) {
        let [x, y, z] = grid.groups;
        self.bind(kernel, params, buffers)
            .dispatch_workgroups(x, y, z);
        self.count_dispatch();
    }

    /// Like `dispatch`, with the workgroup grid read on the GPU from `args` at byte `offset`
    /// (three u32: x, y, z; written earlier in the recording).
    pub fn dispatch_indirect<P: Pod>(
        &mut self,
        kernel: &Kernel<P>,
        args: &wgpu::Buffer,
        offset: u64,
        params: &P,
        buffers: &[&wgpu::Buffer],
    ) {
        self.bind(kernel, params, buffers)
            .dispatch_workgroups_indirect(args, offset);
        self.count_dispatch();
    }

    fn count_dispatch(&mut self) {
        if let Some(count) = self
            .timer
            .as_deref_mut()
            .and_then(GpuTimer::last_dispatches)
        {
            *count += 1;
        }
    }

    /// Binds `kernel`, its parameters and buffers in the pass its dispatch goes into; that pass.
    fn bind<P: Pod>(
        &mut self,
        kernel: &Kernel<P>,
        params: &P,
        buffers: &[&wgpu::Buffer],
    ) -> &mut wgpu::ComputePass<'static> {
        let (chunk, offset) = self.params.push(self.ctx, params);
        let mut bound = Vec::with_capacity(buffers.len() + 1);
        bound.push(&chunk);
        bound.extend_from_slice(buffers);
        let group = kernel.bind_group(self.ctx, &bound);
        let pass = self.pass_for(kernel.info.name);
        pass.set_pipeline(&kernel.compiled.pipeline);
        pass.set_bind_group(0, &group, &[offset]);
        pass
    }
}
