fn main() {
    println!("cargo:rerun-if-changed=wrapper.h");
    // volcast: rebuild when the vendored C++ changes (see VOLCAST.md).
    println!("cargo:rerun-if-changed=charls/src");
    println!("cargo:rerun-if-changed=charls/include");

    #[cfg(not(feature = "vcpkg"))]
    build_with_cc();

    #[cfg(feature = "vcpkg")]
    vcpkg::Config::new()
        .emit_includes(true)
        .find_package("charls")
        .unwrap();
}

/// volcast: CharLS's eight translation units compiled with the `cc` crate instead of CMake, so that building
/// volcast needs only a C++ compiler (see VOLCAST.md). The defines and flags are those of
/// `charls/src/CMakeLists.txt` for a static library: C++14, `CHARLS_STATIC`, `CHARLS_LIBRARY_BUILD`, hidden
/// visibility.
#[cfg(not(feature = "vcpkg"))]
fn build_with_cc() {
    const SOURCES: [&str; 8] = [
        "charls_jpegls_decoder.cpp",
        "charls_jpegls_encoder.cpp",
        "jpegls_error.cpp",
        "jpegls.cpp",
        "jpeg_stream_reader.cpp",
        "jpeg_stream_writer.cpp",
        "validate_spiff_header.cpp",
        "version.cpp",
    ];
    let mut build = cc::Build::new();
    build
        .cpp(true)
        .std("c++14")
        .include("charls/include")
        .define("CHARLS_STATIC", None)
        .define("CHARLS_LIBRARY_BUILD", None)
        .flag_if_supported("-fvisibility=hidden")
        .flag_if_supported("-fvisibility-inlines-hidden")
        .warnings(false);
    for source in SOURCES {
        build.file(format!("charls/src/{source}"));
    }
    build.compile("charls");
}
