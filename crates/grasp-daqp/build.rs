//! Compiles DAQP from the C sources that `scripts/fetch_daqp.sh` puts in
//! `target/daqp/csrc` (or `$DAQP_SRC`), with the shim beside this file. Without them
//! the crate builds empty and its benchmark says how to fetch them.

use std::path::PathBuf;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(daqp)");
    println!("cargo::rerun-if-env-changed=DAQP_SRC");
    println!("cargo::rerun-if-changed=shim.c");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let src = std::env::var_os("DAQP_SRC")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target/daqp/csrc"));
    println!("cargo::rerun-if-changed={}", src.display());
    let Ok(entries) = std::fs::read_dir(src.join("src")) else {
        return;
    };
    let mut build = cc::Build::new();
    for e in entries.flatten() {
        let p = e.path();
        if p.extension().is_some_and(|x| x == "c") {
            build.file(p);
        }
    }
    build
        .file("shim.c")
        .include(src.join("include"))
        .define("PROFILING", None)
        .opt_level(3)
        .warnings(false)
        .compile("daqp");
    println!("cargo::rustc-cfg=daqp");
}
