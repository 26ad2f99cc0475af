//! The server compiles in the files of `docs/` (`rust_embed`): rebuild when
//! that folder changes, a file added or removed included.

fn main() {
    println!("cargo:rerun-if-changed=../../docs");
    println!("cargo:rerun-if-changed=build.rs");
}
