//! The uniffi generator, built from the same uniffi version as the library so the two agree.
fn main() {
    uniffi::uniffi_bindgen_main()
}
