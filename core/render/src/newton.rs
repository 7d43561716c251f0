//! The constants of the Newton iteration on a face's basis surface (`shaders/ray_newton.wgsl`,
//! paper 001 §3.4.2.a) that the CPU side needs: object filling and ray casting converge to
//! the same tolerance, and the ray caster's seed boxes are inflated by it and costed by its
//! step count. Kept below all three so that none reaches into another for them.

/// Newton's convergence tolerance relative to the part's box diagonal (paper 001 figure 18
/// uses 0.001 mm on parts of some 100 mm: 10⁻⁵).
pub const NEWTON_TOLERANCE: f64 = 1e-5;

/// Newton's most steps (`RAY_NEWTON_ITERATIONS` in `shaders/ray_newton.wgsl`).
pub const NEWTON_STEPS: u32 = 12;
