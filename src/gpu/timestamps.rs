//! Kernel times from timestamp queries: one timestamp after every dispatch of
//! a submission, each interval credited to the kernel that ended it.

use super::context::Context;
use ash::vk;
use std::time::Duration;

pub const MAX_QUERIES: u32 = 512;

pub struct Timestamps {
    pool: vk::QueryPool,
    /// Kernel name for each timestamp after the first of this submission.
    labels: Vec<&'static str>,
    period_ns: f64,
    enabled: bool,
    pub totals: Vec<(&'static str, Duration)>,
}

impl Timestamps {
    pub fn new(ctx: &Context) -> anyhow::Result<Timestamps> {
        let enabled = ctx.timestamp_valid_bits > 0 && ctx.properties.limits.timestamp_period > 0.0;
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(MAX_QUERIES);
        // SAFETY: valid device and create info.
        let pool = unsafe { ctx.device.create_query_pool(&info, None) }?;
        Ok(Timestamps {
            pool,
            labels: Vec::new(),
            period_ns: ctx.properties.limits.timestamp_period as f64,
            enabled,
            totals: Vec::new(),
        })
    }

    /// Starts a submission: resets the pool and writes the first timestamp.
    pub fn begin(&mut self, ctx: &Context, cmd: vk::CommandBuffer) {
        self.labels.clear();
        if !self.enabled {
            return;
        }
        // SAFETY: cmd is recording; the pool is not in use by pending work.
        unsafe {
            ctx.device
                .cmd_reset_query_pool(cmd, self.pool, 0, MAX_QUERIES);
            ctx.device.cmd_write_timestamp(
                cmd,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                self.pool,
                0,
            );
        }
    }

    /// Marks the end of `kernel`'s dispatch.
    pub fn mark(&mut self, ctx: &Context, cmd: vk::CommandBuffer, kernel: &'static str) {
        if !self.enabled || self.labels.len() + 1 >= MAX_QUERIES as usize {
            return;
        }
        self.labels.push(kernel);
        let query = self.labels.len() as u32;
        // SAFETY: cmd is recording; query < MAX_QUERIES.
        unsafe {
            ctx.device.cmd_write_timestamp(
                cmd,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                self.pool,
                query,
            )
        };
    }

    /// After the submission completed: adds its intervals to the totals.
    pub fn collect(&mut self, ctx: &Context) -> anyhow::Result<()> {
        if !self.enabled || self.labels.is_empty() {
            return Ok(());
        }
        let mut values = vec![0u64; self.labels.len() + 1];
        // SAFETY: the submission that wrote these queries has completed.
        unsafe {
            ctx.device.get_query_pool_results(
                self.pool,
                0,
                &mut values,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }?;
        for (i, label) in self.labels.iter().enumerate() {
            let ticks = values[i + 1].saturating_sub(values[i]);
            let d = Duration::from_nanos((ticks as f64 * self.period_ns) as u64);
            match self.totals.iter_mut().find(|(n, _)| n == label) {
                Some((_, total)) => *total += d,
                None => self.totals.push((label, d)),
            }
        }
        self.labels.clear();
        Ok(())
    }

    pub fn destroy(&mut self, ctx: &Context) {
        // SAFETY: no pending work uses the pool.
        unsafe { ctx.device.destroy_query_pool(self.pool, None) };
    }
}
