//! The CPU's vector extensions, detected once per process. Hot loops written as plain
//! scalar Rust are entered through [`pulp::x86::V3::vectorize`] where the CPU has AVX2 and
//! FMA, so the compiler may use 256-bit registers for them; Rust never fuses a multiply and
//! an add on its own, so the results are bit for bit those of the baseline build. No
//! `unsafe` here, and the binary still runs on any x86-64 (and elsewhere: no token).

/// The AVX2 + FMA ("x86-64-v3") token where this CPU has them, else `None`.
#[cfg(target_arch = "x86_64")]
pub(crate) fn v3() -> Option<pulp::x86::V3> {
    static V3: std::sync::OnceLock<Option<pulp::x86::V3>> = std::sync::OnceLock::new();
    *V3.get_or_init(pulp::x86::V3::try_new)
}
