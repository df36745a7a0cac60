//! Property tests: inscribed cones lie inside the exact cones, vertices lie on them,
//! the pseudo-inverse satisfies `A Z A = A`, and the model's decomposition (QR,
//! complete orthogonal or SVD) is the SVD's.

use grasp_core::cone::{inscribed_cone, Linearization, SfceSpacing};
use grasp_core::linalg::{decompose, rank, svd, RankThreshold};
use grasp_core::{ContactModel, Matrix};
use proptest::prelude::*;

fn model() -> impl Strategy<Value = ContactModel> {
    prop_oneof![
        (0.05f64..2.0).prop_map(|mu| ContactModel::Pcwf { mu }),
        (0.05f64..2.0, 0.001f64..0.5)
            .prop_map(|(mu, mu_torsion)| ContactModel::SfcLinear { mu, mu_torsion }),
        (0.05f64..2.0, 0.001f64..0.5)
            .prop_map(|(mu, mu_torsion)| ContactModel::SfcElliptic { mu, mu_torsion }),
    ]
}

fn lin() -> impl Strategy<Value = Linearization> {
    (3usize..40, 1usize..6, any::<bool>()).prop_map(|(sides, latitudes, u)| Linearization {
        sides,
        latitudes,
        sfce_spacing: if u {
            SfceSpacing::Uniform
        } else {
            SfceSpacing::Paper
        },
    })
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 512,
        // Fixed seed: CI and every developer see the same cases (STYLE.md).
        rng_seed: proptest::test_runner::RngSeed::Fixed(21),
        ..ProptestConfig::default()
    })]

    /// Walk from the cone's axis along a random direction in the fz = 1 slice to the
    /// polytope's boundary: that point, and so every point of the polytope, is inside
    /// the exact cone.
    #[test]
    fn linearised_cone_points_satisfy_the_exact_cone(m in model(), l in lin(),
                                                     dir in prop::array::uniform3(-1.0f64..1.0)) {
        prop_assume!(dir.iter().map(|x| x * x).sum::<f64>() > 1e-6);
        let cone = inscribed_cone(&m, &l);
        let dim = m.dim();
        let mut d = vec![0.0; dim];
        d[0] = dir[0];
        d[1] = dir[1];
        if dim == 4 { d[3] = dir[2]; }
        let mut axis = vec![0.0; dim];
        axis[2] = 1.0;
        // Largest t with faces·(axis + t d) ≥ 0.
        let mut t = f64::INFINITY;
        for i in 0..cone.faces.nrows() {
            let r = cone.faces.row(i);
            let (a0, ad) = (grasp_core::matrix::dot(r, &axis), grasp_core::matrix::dot(r, &d));
            if ad < 0.0 { t = t.min(a0 / -ad); }
        }
        prop_assert!(t.is_finite() && t > 0.0);
        let f: Vec<f64> = axis.iter().zip(&d).map(|(a, b)| a + t * b).collect();
        // On the polytope's boundary: inside or on the exact cone, to rounding.
        prop_assert!(m.gauge(&f) <= 1.0 + 1e-12, "{m:?} {l:?} gauge {}", m.gauge(&f));
    }

    /// Vertices lie on the exact cone and satisfy every face.
    #[test]
    fn vertices_lie_on_the_exact_cone(m in model(), l in lin()) {
        let cone = inscribed_cone(&m, &l);
        for v in cone.vertices.as_slice().chunks_exact(m.dim()) {
            prop_assert!((m.gauge(v) - 1.0).abs() < 1e-12);
            let worst = cone.faces.mul_vec(v).into_iter().fold(f64::INFINITY, f64::min);
            prop_assert!(worst > -1e-12);
        }
    }

    /// `A Z A = A` for the SVD pseudo-inverse, including rank-deficient A.
    #[test]
    fn pseudo_inverse_reproduces_a(rows in 2usize..12, cols in 2usize..12, rank_cut in 0usize..3,
                                   seed in prop::collection::vec(-1.0f64..1.0, 144)) {
        let b = Matrix::from_fn(rows, cols, |i, j| seed[i * 12 + j]);
        // Make the last `rank_cut` columns copies of the first: rank deficiency.
        let a = Matrix::from_fn(rows, cols, |i, j| if j + rank_cut >= cols { b[(i, 0)] } else { b[(i, j)] });
        let d = svd(&a).unwrap();
        let z = d.pseudo_inverse(1e-9);
        let aza = a.matmul(&z).matmul(&a);
        let tol = 1e3 * f64::EPSILON * (rows.max(cols) as f64) * a.max_abs() ;
        for (x, y) in aza.as_slice().iter().zip(a.as_slice()) {
            prop_assert!((x - y).abs() <= tol, "{x} vs {y}");
        }
    }

    /// [`decompose`] on rank-deficient and full-rank matrices of every shape, with
    /// columns scaled over six decades: the SVD's rank (by [`rank`] too), its
    /// pseudo-inverse, and orthonormal bases of the four subspaces with `A N = 0` and
    /// `U⊥ᵀ A = 0`. The tolerance scales with ε, the size and ‖A‖ over σ_r.
    #[test]
    fn decompose_is_the_svd(rows in 1usize..14, cols in 1usize..14, r in 0usize..14,
                            decades in 0i32..6,
                            seed in prop::collection::vec(-1.0f64..1.0, 2 * 14 * 14)) {
        let r = r.min(rows).min(cols);
        let b = Matrix::from_fn(rows, r, |i, j| seed[i * 14 + j]);
        let c = Matrix::from_fn(r, cols, |i, j| seed[196 + i * 14 + j] * 10f64.powi((j as i32 * decades) / cols.max(1) as i32));
        let a = b.matmul(&c);
        let thr = RankThreshold::Relative(1e-9);
        let d = decompose(&a, thr).unwrap();
        let s = svd(&a).unwrap();
        let want = s.rank(1e-9);
        prop_assert_eq!(d.rank(), want);
        prop_assert_eq!(rank(&a, thr).unwrap(), want);
        prop_assert_eq!(d.null_basis.ncols(), cols - want);
        prop_assert_eq!(d.left_null.ncols(), rows - want);
        let n = rows.max(cols) as f64;
        let amax = a.max_abs().max(f64::MIN_POSITIVE);
        for q in [&d.row_basis, &d.null_basis, &d.left_null] {
            let qtq = q.transpose().matmul(q);
            for i in 0..q.ncols() {
                for j in 0..q.ncols() {
                    let e = if i == j { 1.0 } else { 0.0 };
                    prop_assert!((qtq[(i, j)] - e).abs() <= 1e2 * f64::EPSILON * n);
                }
            }
        }
        let tol = 1e2 * f64::EPSILON * n * amax;
        prop_assert!(a.matmul(&d.null_basis).as_slice().iter().all(|x| x.abs() <= tol));
        prop_assert!(d.left_null.transpose().matmul(&a).as_slice().iter().all(|x| x.abs() <= tol));
        if want > 0 {
            // Both pseudo-inverses are accurate to ε κ/σ_r, κ = σ_max/σ_r.
            let (p, q) = (d.pseudo_inverse(), s.pseudo_inverse(1e-9));
            let kappa = s.s[0] / s.s[want - 1];
            let ptol = 1e3 * f64::EPSILON * n * kappa / s.s[want - 1];
            for (x, y) in p.as_slice().iter().zip(q.as_slice()) {
                prop_assert!((x - y).abs() <= ptol, "{} vs {} (tolerance {})", x, y, ptol);
            }
        }
    }
}
