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

    /// Opens a compute pass named `label`, timestamped when the recording has a timer.
    pub fn pass(&mut self, label: &str) -> Pass<'_> {
        debug_assert!(
            !self.resolved,
            "pass '{label}' after the timer was resolved"
        );
        let label = format!("{}{label}", self.prefix);
        let timestamp_writes = self.timer.as_deref_mut().and_then(|t| t.pass(&label));
        let pass = self
            .encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&label),
                timestamp_writes,
            })
            .forget_lifetime();
        Pass {
            pass,
            ctx: self.ctx,
            params: self.params,
            dispatches: self
                .timer
                .as_deref_mut()
                .and_then(GpuTimer::last_dispatches),
        }
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

/// A compute pass of a recording.
pub struct Pass<'r> {
    pass: wgpu::ComputePass<'static>,
    ctx: &'r GpuContext,
    params: &'r mut ParamSlab,
    /// The timed pass's dispatch count (with a timer).
    dispatches: Option<&'r mut u32>,
}

impl<'r> Pass<'r> {
    pub fn ctx(&self) -> &'r GpuContext {
        self.ctx
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
        self.bind(kernel, params, buffers);
        let [x, y, z] = grid.groups;
        self.pass.dispatch_workgroups(x, y, z);
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
        self.bind(kernel, params, buffers);
        self.pass.dispatch_workgroups_indirect(args, offset);
        self.count_dispatch();
    }

    fn count_dispatch(&mut self) {
        if let Some(count) = self.dispatches.as_deref_mut() {
            *count += 1;
        }
    }

    fn bind<P: Pod>(&mut self, kernel: &Kernel<P>, params: &P, buffers: &[&wgpu::Buffer]) {
        let (chunk, offset) = self.params.push(self.ctx, params);
        let mut bound = Vec::with_capacity(buffers.len() + 1);
        bound.push(&chunk);
        bound.extend_from_slice(buffers);
        let group = kernel.bind_group(self.ctx, &bound);
        self.pass.set_pipeline(&kernel.compiled.pipeline);
        self.pass.set_bind_group(0, &group, &[offset]);
    }
}
