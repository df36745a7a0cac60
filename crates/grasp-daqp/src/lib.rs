//! DAQP (Arnström, Bemporad and Axehill's dual active-set solver, C) behind a small
//! safe wrapper, for benchmarking the native solver against it on the same QPs.
//!
//! The C sources are not vendored: `bash scripts/fetch_daqp.sh` downloads DAQP's
//! source distribution from PyPI into `target/daqp`, and the build script compiles it.
//! Without them [`Daqp::available`] is false and [`Daqp::new`] gives `None`.

/// One DAQP problem `min ½ xᵀHx` s.t. `lower ≤ A x ≤ upper`, set up once; each
/// [`Daqp::solve`] takes the bounds in [`Daqp::lower`] and [`Daqp::upper`] and starts
/// from an empty working set (the equalities reactivated).
pub struct Daqp {
    #[cfg(daqp)]
    handle: *mut std::ffi::c_void,
    // The C side keeps pointers into these: they live as long as the handle, and
    // are never reallocated.
    #[cfg_attr(not(daqp), allow(dead_code))]
    h: Vec<f64>,
    #[cfg_attr(not(daqp), allow(dead_code))]
    a: Vec<f64>,
    upper: Vec<f64>,
    lower: Vec<f64>,
    #[cfg_attr(not(daqp), allow(dead_code))]
    sense: Vec<i32>,
    x: Vec<f64>,
    #[cfg_attr(not(daqp), allow(dead_code))]
    lam: Vec<f64>,
}

/// The outcome of one DAQP solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DaqpResult {
    /// DAQP's exit flag (1: optimal).
    pub exitflag: i32,
    /// `½ xᵀHx`.
    pub objective: f64,
    /// DAQP's own solve time, s (without the setup and the bound update).
    pub solve_time: f64,
    /// Iterations.
    pub iterations: i32,
}

/// DAQP's "upper bound absent" value.
pub const INFINITY: f64 = 1e30;

#[cfg(daqp)]
extern "C" {
    fn gt_daqp_setup(
        n: i32,
        m: i32,
        h: *mut f64,
        a: *mut f64,
        bu: *mut f64,
        bl: *mut f64,
        sense: *mut i32,
        primal_tol: f64,
    ) -> *mut std::ffi::c_void;
    fn gt_daqp_solve(
        p: *mut std::ffi::c_void,
        x: *mut f64,
        lam: *mut f64,
        fval: *mut f64,
        solve_time: *mut f64,
        iter: *mut i32,
    ) -> i32;
    fn gt_daqp_free(p: *mut std::ffi::c_void);
}

impl Daqp {
    /// Whether DAQP was compiled in.
    pub fn available() -> bool {
        cfg!(daqp)
    }

    /// Sets up `min ½ xᵀHx` (H n × n, row-major) subject to `lower ≤ A x ≤ upper`
    /// (A m × n, row-major); rows with `equality[i]` hold with equality. `None` when
    /// DAQP is not compiled in or rejects the problem.
    pub fn new(
        n: usize,
        h: Vec<f64>,
        a: Vec<f64>,
        lower: Vec<f64>,
        upper: Vec<f64>,
        equality: &[bool],
        primal_tol: f64,
    ) -> Option<Self> {
        let m = lower.len();
        if h.len() != n * n || a.len() != m * n || upper.len() != m || equality.len() != m {
            return None;
        }
        // DAQP's sense flags: an equality is active and immutable.
        let sense = equality
            .iter()
            .map(|&e| if e { 1 | 4 } else { 0 })
            .collect();
        #[allow(unused_mut)]
        let mut d = Self {
            #[cfg(daqp)]
            handle: std::ptr::null_mut(),
            h,
            a,
            upper,
            lower,
            sense,
            x: vec![0.0; n],
            lam: vec![0.0; m],
        };
        #[cfg(daqp)]
        {
            // SAFETY: every pointer is to a live buffer of the stated size, owned by
            // `d` and never reallocated while the handle lives.
            d.handle = unsafe {
                gt_daqp_setup(
                    n as i32,
                    m as i32,
                    d.h.as_mut_ptr(),
                    d.a.as_mut_ptr(),
                    d.upper.as_mut_ptr(),
                    d.lower.as_mut_ptr(),
                    d.sense.as_mut_ptr(),
                    primal_tol,
                )
            };
            if d.handle.is_null() {
                return None;
            }
            Some(d)
        }
        #[cfg(not(daqp))]
        {
            let _ = (d, primal_tol);
            None
        }
    }

    /// The lower bounds the next solve uses.
    pub fn lower(&mut self) -> &mut [f64] {
        &mut self.lower
    }

    /// The upper bounds the next solve uses.
    pub fn upper(&mut self) -> &mut [f64] {
        &mut self.upper
    }

    /// Solves with the current bounds, from an empty working set.
    pub fn solve(&mut self) -> DaqpResult {
        let (mut objective, mut solve_time, mut iterations) = (f64::NAN, 0.0, 0);
        #[cfg(daqp)]
        // SAFETY: the handle is live, x and lam have n and m entries.
        let exitflag = unsafe {
            gt_daqp_solve(
                self.handle,
                self.x.as_mut_ptr(),
                self.lam.as_mut_ptr(),
                &mut objective,
                &mut solve_time,
                &mut iterations,
            )
        };
        #[cfg(not(daqp))]
        let exitflag = {
            let _ = (&mut objective, &mut solve_time, &mut iterations);
            -1000
        };
        DaqpResult {
            exitflag,
            objective,
            solve_time,
            iterations,
        }
    }

    /// The primal solution of the last solve.
    pub fn x(&self) -> &[f64] {
        &self.x
    }
}

impl Drop for Daqp {
    fn drop(&mut self) {
        #[cfg(daqp)]
        // SAFETY: the handle came from gt_daqp_setup and is freed once.
        unsafe {
            gt_daqp_free(self.handle)
        }
    }
}
