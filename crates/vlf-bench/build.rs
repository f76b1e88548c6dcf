//! Compiles the Embree shim of `vlf-bench peers` when the `embree` feature is on; nothing otherwise.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    #[cfg(feature = "embree")]
    {
        println!("cargo:rerun-if-changed=src/peers/embree_shim.c");
        println!("cargo:rerun-if-changed=src/dynamic/embree_instances.c");
        cc::Build::new()
            .file("src/peers/embree_shim.c")
            .file("src/dynamic/embree_instances.c")
            .opt_level(3)
            .warnings(true)
            .compile("vlf_embree_shim");
        println!("cargo:rustc-link-lib=embree3");
    }
}
