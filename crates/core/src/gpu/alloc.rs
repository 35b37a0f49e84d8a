//! Counters of GPU object creation and uploads, per thread: a frame engine's steady state
//! creates nothing and uploads only what changed, and tests assert that by reading these
//! counters around a frame. Per thread, because tests share one device across threads
//! while each renders on its own.

use std::cell::RefCell;

/// What was created or uploaded on this thread so far.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub buffers: u64,
    pub textures: u64,
    pub bind_groups: u64,
    pub pipelines: u64,
    /// Queue writes (buffer and texture uploads) and their bytes, by resource label.
    pub uploads: Vec<(String, u64)>,
}

impl Counters {
    /// Objects created (buffers, textures, bind groups, pipelines) since `earlier`.
    pub fn created_since(&self, earlier: &Counters) -> u64 {
        (self.buffers + self.textures + self.bind_groups + self.pipelines)
            - (earlier.buffers + earlier.textures + earlier.bind_groups + earlier.pipelines)
    }

    /// Uploads since `earlier`: (label, bytes) in order.
    pub fn uploads_since(&self, earlier: &Counters) -> Vec<(String, u64)> {
        self.uploads[earlier.uploads.len().min(self.uploads.len())..].to_vec()
    }
}

thread_local! {
    static COUNTERS: RefCell<Counters> = RefCell::new(Counters::default());
}

/// A snapshot of this thread's counters.
pub fn counters() -> Counters {
    COUNTERS.with(|c| c.borrow().clone())
}

/// Adds `other` (e.g. the counters of a worker thread that rendered on behalf of this one)
/// to this thread's counters.
pub fn merge(other: Counters) {
    COUNTERS.with(|c| {
        let mut c = c.borrow_mut();
        c.buffers += other.buffers;
        c.textures += other.textures;
        c.bind_groups += other.bind_groups;
        c.pipelines += other.pipelines;
        c.uploads.extend(other.uploads);
    })
}

pub(crate) enum Created {
    Buffer,
    Texture,
    BindGroup,
    Pipeline,
}

pub(crate) fn note(what: Created) {
    COUNTERS.with(|c| {
        let mut c = c.borrow_mut();
        match what {
            Created::Buffer => c.buffers += 1,
            Created::Texture => c.textures += 1,
            Created::BindGroup => c.bind_groups += 1,
            Created::Pipeline => c.pipelines += 1,
        }
    })
}

pub(crate) fn note_upload(label: &str, bytes: u64) {
    COUNTERS.with(|c| {
        let mut c = c.borrow_mut();
        // Keep the log bounded over long animations: only the count matters past that.
        if c.uploads.len() > 1 << 16 {
            c.uploads.clear();
        }
        c.uploads.push((label.to_string(), bytes));
    })
}
