//! The few numerical kernels the networks are made of: matrix products on the `gemm` crate,
//! im2col and its adjoint as contiguous row copies, and a fixed two-way split of a batch.
//!
//! Why these and nothing more: a training step of either network is a handful of matrix
//! products, and everything else (patch gathering, bias, batch normalisation, ReLU, the
//! optimiser) is a pass over memory. The products run on `gemm`'s single-threaded kernels
//! (AVX2 + FMA here); the second core is used by splitting a batch into two fixed halves
//! ([`join`]), whatever the number of threads, so one or two threads give the same bits. A
//! training loop runs inside [`sim::team::on_pool_awake`] (the one home of keeping a pool's
//! threads awake), so the second half of a split finds a thread awake to take it.
//!
//! Every pass runs with subnormal floats flushed to zero ([`without_subnormals`]): Adam's
//! moments of weights that no input reaches decay into them over a few thousand steps, and
//! an Intel core takes a slow assist on every subnormal operand (measured here: the
//! small network's step went from 3 ms to 20 ms by step 4,000 of a run).

use gemm::{Parallelism, gemm};

/// `c[m x n] (+)= a[m x k] * b[k x n]`, every matrix row-major; `c` is overwritten unless
/// `accumulate`.
pub fn matmul(c: &mut [f32], a: &[f32], b: &[f32], (m, k, n): (usize, usize, usize), accumulate: bool) {
    assert!(
        a.len() >= m * k && b.len() >= k * n && c.len() >= m * n,
        "matmul shapes"
    );
    // SAFETY: the asserts keep every index the strides reach inside the slices.
    unsafe { product(c, (a, k as isize, 1), (b, n as isize, 1), (m, k, n), accumulate) }
}

/// `c[m x n] (+)= a^T * b` with `a` stored `[k x m]` and `b` `[k x n]`, row-major.
pub fn matmul_tn(c: &mut [f32], a: &[f32], b: &[f32], (m, k, n): (usize, usize, usize), accumulate: bool) {
    assert!(
        a.len() >= k * m && b.len() >= k * n && c.len() >= m * n,
        "matmul_tn shapes"
    );
    // SAFETY: as in `matmul`; `a` is read through transposed strides.
    unsafe { product(c, (a, 1, m as isize), (b, n as isize, 1), (m, k, n), accumulate) }
}

/// `c[m x n] (+)= a * b^T` with `a` stored `[m x k]` and `b` `[n x k]`, row-major.
pub fn matmul_nt(c: &mut [f32], a: &[f32], b: &[f32], (m, k, n): (usize, usize, usize), accumulate: bool) {
    assert!(
        a.len() >= m * k && b.len() >= n * k && c.len() >= m * n,
        "matmul_nt shapes"
    );
    // SAFETY: as in `matmul`; `b` is read through transposed strides.
    unsafe { product(c, (a, k as isize, 1), (b, 1, k as isize), (m, k, n), accumulate) }
}

/// A matrix operand: values, row stride, column stride.
type Operand<'a> = (&'a [f32], isize, isize);

/// # Safety
/// Every `row * rs + col * cs` of each operand within its shape must index its slice.
unsafe fn product(
    c: &mut [f32],
    (a, a_rs, a_cs): Operand<'_>,
    (b, b_rs, b_cs): Operand<'_>,
    (m, k, n): (usize, usize, usize),
    accumulate: bool,
) {
    if m == 0 || n == 0 {
        return;
    }
    if k == 0 {
        if !accumulate {
            c[..m * n].fill(0.0);
        }
        return;
    }
    // SAFETY: the caller's contract; gemm computes dst = alpha * dst + beta * lhs * rhs.
    unsafe {
        gemm(
            m,
            n,
            k,
            c.as_mut_ptr(),
            1,
            n as isize,
            accumulate,
            a.as_ptr(),
            a_cs,
            a_rs,
            b.as_ptr(),
            b_cs,
            b_rs,
            1.0,
            1.0,
            false,
            false,
            false,
            Parallelism::None,
        )
    }
}

/// A `k x k` stride-`s` convolution's geometry over a `rows x cols x ch` input (channel
/// fastest): patches are `(kr, kc, c)` vectors, outputs `(row, column, channel out)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConvGeometry {
    /// Input rows.
    pub rows: usize,
    /// Input columns.
    pub cols: usize,
    /// Input channels.
    pub ch: usize,
    /// Filter side.
    pub k: usize,
    /// Stride.
    pub s: usize,
    /// Output rows.
    pub out_rows: usize,
    /// Output columns.
    pub out_cols: usize,
}

impl ConvGeometry {
    /// The geometry, if the input holds at least one filter.
    pub fn new(rows: usize, cols: usize, ch: usize, k: usize, s: usize) -> Option<ConvGeometry> {
        (rows >= k && cols >= k && k > 0 && s > 0).then(|| ConvGeometry {
            rows,
            cols,
            ch,
            k,
            s,
            out_rows: (rows - k) / s + 1,
            out_cols: (cols - k) / s + 1,
        })
    }

    /// Values per input sample.
    pub fn input_len(&self) -> usize {
        self.rows * self.cols * self.ch
    }

    /// Output positions per sample.
    pub fn positions(&self) -> usize {
        self.out_rows * self.out_cols
    }

    /// Values per patch.
    pub fn patch(&self) -> usize {
        self.k * self.k * self.ch
    }

    /// Gathers every patch of the samples in `x` (`samples * input_len`) into `cols`
    /// (`samples * positions` rows of `patch`): `k` contiguous copies of `k * ch` values each.
    pub fn im2col(&self, x: &[f32], cols: &mut [f32]) {
        // The runs of the paper network (8 x 3 and 4 x 16 values) and of the conv network
        // (a cell of RGB: 4 x 3 on the compact screen, 16 x 3 on the paper's) as fixed-size
        // copies: inline vector moves rather than a call to memcpy each.
        match self.k * self.ch {
            12 => self.gather::<12>(x, cols),
            24 => self.gather::<24>(x, cols),
            48 => self.gather::<48>(x, cols),
            64 => self.gather::<64>(x, cols),
            _ => self.gather::<0>(x, cols),
        }
    }

    /// [`ConvGeometry::im2col`] for runs of `RUN` values (0: any length).
    #[inline(always)]
    fn gather<const RUN: usize>(&self, x: &[f32], cols: &mut [f32]) {
        let run = self.k * self.ch;
        let patch = self.patch();
        let mut out = cols.chunks_exact_mut(patch);
        for sample in x.chunks_exact(self.input_len()) {
            for or in 0..self.out_rows {
                for oc in 0..self.out_cols {
                    let row = out.next().expect("cols holds every patch");
                    for (kr, dst) in row.chunks_exact_mut(run).enumerate() {
                        let start = ((or * self.s + kr) * self.cols + oc * self.s) * self.ch;
                        let src = &sample[start..start + run];
                        if RUN == 0 {
                            dst.copy_from_slice(src);
                        } else {
                            let dst: &mut [f32; RUN] = dst.try_into().expect("a run");
                            *dst = src.try_into().expect("a run");
                        }
                    }
                }
            }
        }
    }

    /// The adjoint of [`ConvGeometry::im2col`]: adds each patch row of `cols` back into the
    /// input positions it came from, over `dx` (zeroed first), in a fixed order.
    pub fn col2im(&self, cols: &[f32], dx: &mut [f32]) {
        dx.fill(0.0);
        let run = self.k * self.ch;
        let patch = self.patch();
        let mut rows = cols.chunks_exact(patch);
        for sample in dx.chunks_exact_mut(self.input_len()) {
            for or in 0..self.out_rows {
                for oc in 0..self.out_cols {
                    let row = rows.next().expect("cols holds every patch");
                    for kr in 0..self.k {
                        let start = ((or * self.s + kr) * self.cols + oc * self.s) * self.ch;
                        let src = &row[kr * run..(kr + 1) * run];
                        for (d, &g) in sample[start..start + run].iter_mut().zip(src) {
                            *d += g;
                        }
                    }
                }
            }
        }
    }
}

/// Declares `fn $name(args) -> ret` that runs `$generic` (an `#[inline(always)]` function
/// of the same arguments) compiled for AVX2 when the CPU has it (the std library caches
/// the check), else as it is.
///
/// Why: the build targets baseline x86-64 (SSE2), and the element-wise passes (sparse
/// rows, batch normalisation, the optimiser) run about twice as fast on 256-bit vectors.
/// Without FMA contraction both versions give the same bits.
macro_rules! avx2_dispatch {
    ($(#[$m:meta])* $vis:vis fn $name:ident => $generic:ident ($($arg:ident : $ty:ty),* $(,)?) $(-> $ret:ty)?) => {
        $(#[$m])*
        $vis fn $name($($arg: $ty),*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2")]
                fn fast($($arg: $ty),*) $(-> $ret)? {
                    $generic($($arg),*)
                }
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the CPU has AVX2, checked just above.
                    return unsafe { fast($($arg),*) };
                }
            }
            $generic($($arg),*)
        }
    };
}
pub(crate) use avx2_dispatch;

/// `tanh` of every value, in place, as a rational function: Eigen's and PyTorch's CPU
/// approximation (a 13th over a 6th degree polynomial on `[-7.9, 7.9]`, clamped outside),
/// within a few units in the last place of `f32::tanh`. Why: libm's `tanhf` is a call per
/// value and costs tens of nanoseconds; this is a dozen multiply-adds that vectorise.
pub fn tanh_in_place(values: &mut [f32]) {
    tanh_dispatch(values);
}

avx2_dispatch! {
    fn tanh_dispatch => tanh_any(values: &mut [f32])
}

#[inline(always)]
fn tanh_any(values: &mut [f32]) {
    const CLAMP: f32 = 7.905_311;
    const A: [f32; 7] = [
        4.893_524_6e-3,
        6.372_619_3e-4,
        1.485_722_4e-5,
        5.122_297e-8,
        -8.604_672e-11,
        2.000_188e-13,
        -2.760_768_5e-16,
    ];
    const B: [f32; 4] = [4.893_525e-3, 2.268_434_6e-3, 1.185_347_1e-4, 1.198_258_4e-6];
    for v in values.iter_mut() {
        let x = v.clamp(-CLAMP, CLAMP);
        let x2 = x * x;
        let p = ((((((A[6] * x2 + A[5]) * x2 + A[4]) * x2 + A[3]) * x2 + A[2]) * x2 + A[1]) * x2 + A[0]) * x;
        let q = ((B[3] * x2 + B[2]) * x2 + B[1]) * x2 + B[0];
        *v = p / q;
    }
}

/// How many fixed parts a batch of `batch` samples is split into: two when each half
/// carries at least `min_half` samples' worth of work, else one. It depends on the work
/// only, never on the threads, so results do not either.
pub fn parts(batch: usize, min_half: usize) -> usize {
    if batch >= 2 * min_half.max(1) { 2 } else { 1 }
}

/// Where part `p` of `parts` begins in a batch of `batch` samples.
pub fn part_start(batch: usize, parts: usize, p: usize) -> usize {
    batch * p / parts
}

/// Runs `a` and `b`, on two threads when the current rayon pool has them, each
/// [`without_subnormals`] (whichever thread it lands on).
pub fn join<A: FnOnce() -> RA + Send, B: FnOnce() -> RB + Send, RA: Send, RB: Send>(a: A, b: B) -> (RA, RB) {
    let (a, b) = (|| without_subnormals(a), || without_subnormals(b));
    if rayon::current_num_threads() > 1 {
        rayon::join(a, b)
    } else {
        (a(), b())
    }
}

/// Runs the two halves of a split into `parts` ([`parts`]): with two, as [`join`] does;
/// with one, `a` then `b` on this thread (`b`'s half then empty), also
/// [`without_subnormals`].
pub fn both<A: FnOnce() + Send, B: FnOnce() + Send>(parts: usize, a: A, b: B) {
    if parts == 2 {
        join(a, b);
    } else {
        without_subnormals(|| {
            a();
            b();
        });
    }
}

/// Runs `f` with subnormal floats flushed to zero, as inputs and as results (the x86-64
/// control bits FTZ and DAZ, PyTorch's `set_flush_denormal(True)`), and puts the thread's
/// previous mode back after: a caller's own arithmetic, a Python interpreter's say, is left
/// as it was. Where the CPU is not x86-64, `f` runs as it is.
///
/// Why: the networks' values never need magnitudes below 1e-38, and on Intel cores each
/// subnormal operand costs a microcode assist (module docs). The mode is part of the
/// arithmetic, so every pass runs under it and results stay the same bits on every run.
pub fn without_subnormals<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    {
        /// MXCSR's flush-to-zero (bit 15) and denormals-are-zero (bit 6) bits.
        const FTZ_DAZ: u32 = 0x8040;
        let mut before = 0u32;
        // SAFETY: stmxcsr stores the 32-bit control register at a valid, aligned address.
        unsafe { std::arch::asm!("stmxcsr [{}]", in(reg) &mut before, options(nostack, preserves_flags)) };
        let flushing = before | FTZ_DAZ;
        // SAFETY: ldmxcsr loads a valid control word: the current one with two mode bits set.
        unsafe { std::arch::asm!("ldmxcsr [{}]", in(reg) &flushing, options(nostack, preserves_flags, readonly)) };
        let result = opaque(f);
        // SAFETY: as above, the word the thread had.
        unsafe { std::arch::asm!("ldmxcsr [{}]", in(reg) &before, options(nostack, preserves_flags, readonly)) };
        result
    }
    #[cfg(not(target_arch = "x86_64"))]
    f()
}

/// Calls `f` behind a call the compiler does not inline, so that none of its arithmetic
/// is moved across the mode switches around it (the compiler does not know the mode).
#[inline(never)]
fn opaque<R>(f: impl FnOnce() -> R) -> R {
    f()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_on_the_awake_pool_give_their_results() {
        use sim::team::on_pool_awake;
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let sums = pool.install(|| {
            on_pool_awake(|| {
                (0..200)
                    .map(|k: u64| {
                        let (a, b) = join(|| (0..k).sum::<u64>(), || (k..2 * k).sum::<u64>());
                        a + b
                    })
                    .sum::<u64>()
            })
        });
        assert_eq!(sums, (0..200u64).map(|k| (0..2 * k).sum::<u64>()).sum::<u64>());
    }

    fn naive(a: &[f32], b: &[f32], m: usize, k: usize, n: usize) -> Vec<f32> {
        let mut c = vec![0.0; m * n];
        for i in 0..m {
            for j in 0..n {
                c[i * n + j] = (0..k)
                    .map(|l| f64::from(a[i * k + l]) * f64::from(b[l * n + j]))
                    .sum::<f64>() as f32;
            }
        }
        c
    }

    fn values(n: usize, seed: f32) -> Vec<f32> {
        (0..n).map(|i| ((i as f32 + seed) * 0.618).sin()).collect()
    }

    fn transpose(a: &[f32], rows: usize, cols: usize) -> Vec<f32> {
        (0..cols * rows).map(|i| a[(i % rows) * cols + i / rows]).collect()
    }

    #[test]
    fn subnormals_flush_to_zero_inside_and_the_threads_mode_comes_back() {
        use std::hint::black_box;
        let tiny = f32::MIN_POSITIVE / 4.0;
        assert!(tiny.is_subnormal());
        let product = || black_box(tiny) * black_box(1.0f32);
        let inside = without_subnormals(product);
        let (a, b) = join(product, product);
        if cfg!(target_arch = "x86_64") {
            assert_eq!((inside, a, b), (0.0, 0.0, 0.0));
        }
        assert_eq!(product(), tiny, "the caller's mode is restored");
    }

    #[test]
    fn the_three_products_equal_a_naive_one() {
        for (m, k, n) in [(1, 1, 1), (7, 13, 5), (64, 256, 8), (33, 3872, 17)] {
            let (a, b) = (values(m * k, 1.0), values(k * n, 2.0));
            let want = naive(&a, &b, m, k, n);
            let close = |got: &[f32]| {
                got.iter()
                    .zip(&want)
                    .all(|(g, w)| (g - w).abs() <= 1e-4 * (1.0 + w.abs()))
            };
            let mut c = vec![9.0; m * n];
            matmul(&mut c, &a, &b, (m, k, n), false);
            assert!(close(&c), "{m} {k} {n}");
            matmul_tn(&mut c, &transpose(&a, m, k), &b, (m, k, n), false);
            assert!(close(&c), "tn {m} {k} {n}");
            matmul_nt(&mut c, &a, &transpose(&b, k, n), (m, k, n), false);
            assert!(close(&c), "nt {m} {k} {n}");
            // Accumulating adds the product to what is there.
            let mut c2 = c.clone();
            matmul(&mut c2, &a, &b, (m, k, n), true);
            assert!(
                c2.iter()
                    .zip(&c)
                    .all(|(x, y)| (x - 2.0 * y).abs() <= 1e-4 * (1.0 + y.abs()))
            );
        }
    }

    #[test]
    fn im2col_gathers_patches_and_col2im_is_its_adjoint() {
        let g = ConvGeometry::new(5, 6, 2, 3, 2).unwrap();
        assert_eq!((g.out_rows, g.out_cols, g.patch()), (2, 2, 18));
        let x = values(2 * g.input_len(), 0.5);
        let mut cols = vec![0.0; 2 * g.positions() * g.patch()];
        g.im2col(&x, &mut cols);
        // Patch (sample 1, output (1, 0)), element (kr 2, kc 1, c 1).
        let at = (g.positions() + g.out_cols) * g.patch() + (2 * 3 + 1) * 2 + 1;
        assert_eq!(cols[at], x[g.input_len() + ((2 + 2) * 6 + 1) * 2 + 1]);
        // <im2col(x), y> = <x, col2im(y)>.
        let y = values(cols.len(), 3.0);
        let mut dx = vec![1.0; x.len()];
        g.col2im(&y, &mut dx);
        let lhs: f64 = cols.iter().zip(&y).map(|(a, b)| f64::from(a * b)).sum();
        let rhs: f64 = x.iter().zip(&dx).map(|(a, b)| f64::from(a * b)).sum();
        assert!((lhs - rhs).abs() < 1e-4, "{lhs} {rhs}");
        assert!(ConvGeometry::new(2, 5, 1, 3, 1).is_none());
    }

    #[test]
    fn the_rational_tanh_is_tanh() {
        let mut xs: Vec<f32> = (-2000..=2000).map(|i| i as f32 / 100.0).collect();
        let want: Vec<f32> = xs.iter().map(|x| x.tanh()).collect();
        tanh_in_place(&mut xs);
        for (got, want) in xs.iter().zip(&want) {
            assert!((got - want).abs() < 1e-6, "{got} {want}");
        }
    }

    #[test]
    fn a_split_depends_on_the_work_only() {
        assert_eq!(parts(1, 4), 1);
        assert_eq!(parts(8, 4), 2);
        assert_eq!(
            (part_start(7, 2, 0), part_start(7, 2, 1), part_start(7, 2, 2)),
            (0, 3, 7)
        );
    }
}
