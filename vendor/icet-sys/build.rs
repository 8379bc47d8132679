//! Builds the vendored IceT core, its compositing strategies and its MPI communicator
//! (vendor/icet-sys/VOLCAST.md) into a static library with the cc crate.
//!
//! IceT's MPI layer and radix-k include `<mpi.h>`, so MPI's C headers must be installed: they are found with
//! `mpicc --showme:incdirs` (Open MPI; `$MPICC` overrides the wrapper's name), then `pkg-config --cflags` for
//! `ompi-c` or `mpich`. libmpi itself is linked by the `mpi` crate in the final binary; the search path and
//! `-lmpi` are printed here as well so that a binary linking icet-sys alone still resolves IceT's MPI calls.

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

/// IceT's C sources: the core (`src/ice-t`), the strategies, and the MPI communicator. The OpenGL layers are
/// not vendored.
const SOURCE_DIRS: [&str; 2] = ["icet/src/ice-t", "icet/src/strategies"];
const MPI_SOURCE: &str = "icet/src/communication/mpi.c";

fn main() {
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR"));

    // icet/include/IceTConfig.h is written by hand for LP64 Linux (long and pointers of 8 bytes); refuse a
    // target where its type sizes would be wrong rather than build a library with mismatched typedefs.
    let pointer_width = env::var("CARGO_CFG_TARGET_POINTER_WIDTH").unwrap_or_default();
    let target_os = env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if pointer_width != "64" || target_os == "windows" {
        panic!(
            "icet-sys: icet/include/IceTConfig.h is written for LP64 Unix targets (x86_64/aarch64 Linux); \
             this target has {pointer_width}-bit pointers on {target_os}"
        );
    }

    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=icet");
    println!("cargo:rerun-if-env-changed=MPICC");
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");

    let mpi = probe_mpi().unwrap_or_else(|| {
        panic!(
            "icet-sys needs MPI's C headers: install libopenmpi-dev \
             (neither `mpicc --showme:incdirs` nor `pkg-config --cflags ompi-c`/`mpich` found mpi.h)"
        )
    });

    let mut sources = Vec::new();
    for dir in SOURCE_DIRS {
        sources.extend(c_files(&manifest.join(dir)));
    }
    sources.push(manifest.join(MPI_SOURCE));

    let mut build = cc::Build::new();
    build
        .std("c99")
        .include(manifest.join("icet/include")) // the hand-written IceTConfig.h
        .include(manifest.join("icet/src/include"))
        .includes(&mpi.include_dirs)
        // Upstream builds warning-free with -Wall -Wextra (checked with GCC 12); keep other compilers quiet too.
        .warnings(false)
        .extra_warnings(false)
        .flag_if_supported("-w")
        .files(&sources);
    build.compile("icet");

    for dir in &mpi.lib_dirs {
        println!("cargo:rustc-link-search=native={}", dir.display());
    }
    for lib in &mpi.libs {
        println!("cargo:rustc-link-lib={lib}");
    }
    // IceT's core calls floor/ceil/sqrt (upstream links IceTCore against libm on Unix).
    println!("cargo:rustc-link-lib=m");
    // For dependents (DEP_ICET_INCLUDE): IceT's headers, the configured one first.
    println!(
        "cargo:include={}:{}",
        manifest.join("icet/include").display(),
        manifest.join("icet/src/include").display()
    );
}

/// The `.c` files directly in `dir`, sorted so that the archive is reproducible.
fn c_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("icet-sys: cannot read {}: {e}", dir.display()))
        .map(|entry| entry.expect("icet-sys: reading a vendored directory").path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "c"))
        .collect();
    files.sort();
    files
}

struct Mpi {
    include_dirs: Vec<PathBuf>,
    lib_dirs: Vec<PathBuf>,
    libs: Vec<String>,
}

fn probe_mpi() -> Option<Mpi> {
    probe_mpicc().or_else(|| ["ompi-c", "mpich"].into_iter().find_map(probe_pkg_config))
}

/// Open MPI's compiler wrapper: `--showme:incdirs`, `--showme:libdirs`, `--showme:libs`.
fn probe_mpicc() -> Option<Mpi> {
    let mpicc = env::var("MPICC").unwrap_or_else(|_| "mpicc".to_owned());
    let showme = |what: &str| -> Option<Vec<String>> {
        let output = Command::new(&mpicc).arg(format!("--showme:{what}")).output().ok()?;
        if !output.status.success() {
            return None;
        }
        Some(
            String::from_utf8_lossy(&output.stdout)
                .split_whitespace()
                .map(str::to_owned)
                .collect(),
        )
    };
    let include_dirs: Vec<PathBuf> = showme("incdirs")?.into_iter().map(PathBuf::from).collect();
    if !has_mpi_h(&include_dirs) {
        return None;
    }
    let lib_dirs = showme("libdirs")
        .unwrap_or_default()
        .into_iter()
        .map(PathBuf::from)
        .collect();
    let mut libs = showme("libs").unwrap_or_default();
    if libs.is_empty() {
        libs.push("mpi".to_owned());
    }
    Some(Mpi {
        include_dirs,
        lib_dirs,
        libs,
    })
}

/// `pkg-config --cflags --libs <package>`, keeping the -I, -L and -l arguments.
fn probe_pkg_config(package: &str) -> Option<Mpi> {
    let output = Command::new("pkg-config")
        .args(["--cflags", "--libs", package])
        .output()
        .ok()?;
    if !output.status.success() {
        return None;
    }
    let text = String::from_utf8_lossy(&output.stdout).into_owned();
    let mut mpi = Mpi {
        include_dirs: Vec::new(),
        lib_dirs: Vec::new(),
        libs: Vec::new(),
    };
    for arg in text.split_whitespace() {
        if let Some(dir) = arg.strip_prefix("-I") {
            mpi.include_dirs.push(PathBuf::from(dir));
        } else if let Some(dir) = arg.strip_prefix("-L") {
            mpi.lib_dirs.push(PathBuf::from(dir));
        } else if let Some(lib) = arg.strip_prefix("-l") {
            mpi.libs.push(lib.to_owned());
        }
    }
    // pkg-config prints no -I for headers in /usr/include; mpi.h there is found without one.
    let default_dirs = [PathBuf::from("/usr/include")];
    let found = has_mpi_h(&mpi.include_dirs) || (mpi.include_dirs.is_empty() && has_mpi_h(&default_dirs));
    found.then_some(mpi)
}

fn has_mpi_h(dirs: &[PathBuf]) -> bool {
    dirs.iter().any(|dir| dir.join("mpi.h").is_file())
}
