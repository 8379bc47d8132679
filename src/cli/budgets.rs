//! `--host-budget` and `--gpu-budget`: the memory a volume may take, one group of flags for every subcommand that
//! shows a volume (`render`, `view`, `compare`, `info`, `convert`, `bench --scale`).

use super::parse::parse_bytes;
use crate::gpu::Gpu;
use crate::pyramid::budget::Budgets;
use clap::Args;

#[derive(Args, Clone, Copy, Debug, Default)]
pub struct BudgetArgs {
    /// Host memory the voxels may take, like 6G or 512M (default: a quarter of the machine's)
    ///
    /// A larger volume is shown at the finest pyramid level that fits, read level by level from files whose voxels
    /// lie on disk.
    #[arg(long, value_name = "SIZE", value_parser = parse_bytes)]
    pub host_budget: Option<u64>,
    /// Device memory the volume may take, like 1G (default: the device's largest heap)
    ///
    /// The upload included. Over it, `render` streams the volume brick by brick through a pool of half of it, each
    /// brick at the level its size on screen asks; the viewer and movies show the finest pyramid level that fits.
    #[arg(long, value_name = "SIZE", value_parser = parse_bytes, hide_short_help = true)]
    pub gpu_budget: Option<u64>,
}

impl BudgetArgs {
    /// Whether either flag was given.
    pub fn given(&self) -> bool {
        self.host_budget.is_some() || self.gpu_budget.is_some()
    }

    /// The host budget, no device known yet.
    pub fn host(&self) -> Budgets {
        Budgets::host(self.host_budget)
    }

    /// The budgets on `gpu` ([`Gpu::budgets`]).
    pub fn on(&self, gpu: &Gpu) -> Budgets {
        gpu.budgets(self.host_budget, self.gpu_budget)
    }
}
