//! The GPU objects a frame makes, counted as wgpu-core creates them: a `log` logger that reads
//! wgpu-core's own trace lines (`Device::create_buffer -> …`, `Texture::create_view(…) -> …`),
//! on only while [`count`] runs its closure. Creations are counted, not the objects alive
//! after: an object made this frame that replaces last frame's counts, and the staging buffer
//! wgpu makes inside `Queue::write_buffer` does not (it is wgpu's own, not a `create_*` call).
//! [`count`] counts what every thread makes meanwhile; [`count_here`] only the calling
//! thread's: what a frame makes, not what a worker makes while it runs.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicIsize, Ordering};

/// Objects a frame made: buffers, textures, texture views, bind groups, and compute and
/// render pipelines (none should be made on a frame: pipelines are made ahead).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Made {
    pub buffers: isize,
    pub textures: isize,
    pub views: isize,
    pub bind_groups: isize,
    pub compute_pipelines: isize,
    pub render_pipelines: isize,
}

impl Made {
    /// Buffers, textures, views, bind groups: the table's and the CSV's order.
    pub fn counts(&self) -> [isize; 4] {
        [self.buffers, self.textures, self.views, self.bind_groups]
    }

    /// Each count the largest of `self`'s and `b`'s.
    pub fn max(self, b: Made) -> Self {
        Self {
            buffers: self.buffers.max(b.buffers),
            textures: self.textures.max(b.textures),
            views: self.views.max(b.views),
            bind_groups: self.bind_groups.max(b.bind_groups),
            compute_pipelines: self.compute_pipelines.max(b.compute_pipelines),
            render_pipelines: self.render_pipelines.max(b.render_pipelines),
        }
    }

    /// Pipelines, compute and render.
    pub fn pipelines(&self) -> isize {
        self.compute_pipelines + self.render_pipelines
    }
}

/// What wgpu-core's trace line for each creation starts with (`Device::create_buffer(label)`,
/// `Device::create_bind_group -> id`, …), and its counter.
static KINDS: [(&str, AtomicIsize); 6] = [
    ("Device::create_buffer", AtomicIsize::new(0)),
    ("Device::create_texture", AtomicIsize::new(0)),
    ("Texture::create_view", AtomicIsize::new(0)),
    ("Device::create_bind_group", AtomicIsize::new(0)),
    ("Device::create_compute_pipeline", AtomicIsize::new(0)),
    ("Device::create_render_pipeline", AtomicIsize::new(0)),
];

/// Whether only the thread that called [`count_here`] is counted.
static ONLY_HERE: AtomicBool = AtomicBool::new(false);

thread_local! {
    /// Whether this thread is the one [`count_here`] counts.
    static HERE: Cell<bool> = const { Cell::new(false) };
}

struct Counter;

impl log::Log for Counter {
    fn enabled(&self, meta: &log::Metadata) -> bool {
        meta.target().starts_with("wgpu_core")
    }

    fn log(&self, record: &log::Record) {
        if !self.enabled(record.metadata())
            || (ONLY_HERE.load(Ordering::Relaxed) && !HERE.with(Cell::get))
        {
            return;
        }
        let line = record.args().to_string();
        let kind = KINDS.iter().find(|(start, _)| {
            line.strip_prefix(start)
                .is_some_and(|rest| rest.starts_with([' ', '(']))
        });
        if let Some((_, n)) = kind {
            n.fetch_add(1, Ordering::Relaxed);
            if std::env::var_os("VIEWER_MADE_LOG").is_some() {
                eprintln!("made: {line}");
            }
        }
    }

    fn flush(&self) {}
}

static COUNTER: Counter = Counter;

/// Run `f`, counting the objects wgpu creates meanwhile (on every thread). The logger is
/// installed on first use and left at level `Off` outside `count`, so frames not counted pay
/// nothing for it; if the process already has another logger, nothing is counted (`None`).
pub fn count<T>(f: impl FnOnce() -> T) -> (T, Option<Made>) {
    counted(f, false)
}

/// [`count`], counting only what the calling thread makes (a frame, not the workers running
/// meanwhile).
pub fn count_here<T>(f: impl FnOnce() -> T) -> (T, Option<Made>) {
    counted(f, true)
}

fn counted<T>(f: impl FnOnce() -> T, here: bool) -> (T, Option<Made>) {
    let installed = log::set_logger(&COUNTER).is_ok() || is_ours();
    if !installed {
        return (f(), None);
    }
    for (_, n) in &KINDS {
        n.store(0, Ordering::Relaxed);
    }
    ONLY_HERE.store(here, Ordering::Relaxed);
    HERE.with(|h| h.set(here));
    log::set_max_level(log::LevelFilter::Trace);
    let out = f();
    log::set_max_level(log::LevelFilter::Off);
    HERE.with(|h| h.set(false));
    ONLY_HERE.store(false, Ordering::Relaxed);
    let [b, t, v, g, p, r] = std::array::from_fn(|i| KINDS[i].1.load(Ordering::Relaxed));
    let made = Made {
        buffers: b,
        textures: t,
        views: v,
        bind_groups: g,
        compute_pipelines: p,
        render_pipelines: r,
    };
    (out, Some(made))
}

/// Whether the installed logger is this one.
fn is_ours() -> bool {
    std::ptr::addr_eq(log::logger(), &COUNTER as &dyn log::Log)
}
