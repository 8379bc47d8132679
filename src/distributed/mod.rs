//! Sort-last rendering over MPI (issue 34), as ParaView renders image data with IceT: each rank reads and ray-casts
//! its box of the volume (a k-d decomposition into whole bricks, with a ghost layer), and IceT composites the
//! ranks' premultiplied shares in the tree's visibility order. docs/distributed.md states the rules.
//!
//! The decomposition, the order and the last step on rank 0 are pure and built without MPI; the run itself needs
//! the cargo feature `mpi`.

pub mod decompose;
pub mod finish;
#[cfg(feature = "mpi")]
pub mod icet;
pub mod part;
#[cfg(feature = "mpi")]
pub mod run;

/// The ranks `mpirun` (Open MPI, MPICH or a PMI launcher) started this process among, from the environment they
/// set, if any: without the feature `mpi`, such a launch is refused rather than run N times side by side.
pub fn launched_ranks() -> Option<u32> {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"]
        .iter()
        .find_map(|k| std::env::var(k).ok()?.trim().parse().ok())
}
