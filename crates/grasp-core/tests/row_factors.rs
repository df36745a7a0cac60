//! `H X` through the row factors (`S (Z2 X)`, ±X on limit rows) equals the product
//! with the assembled H, to the rounding of the sums, on every bundled grasp, with
//! inscribed and exact cones and torque limits; so does the largest scaled row norm.

use grasp_core::{
    ConeRepr, ContactBlock, GraspModel, InequalityRows, Matrix, ModelOptions, TorqueQp,
};
use grasp_io::load_problem;
use std::path::Path;
use std::sync::Arc;

/// A bundled grasp with torque limits on every `every`-th joint (so that limit rows are
/// covered everywhere), and its inscribed and exact views.
fn views(path: &Path, every: usize) -> (Arc<GraspModel>, [TorqueQp; 2]) {
    let mut p = load_problem(path).unwrap();
    let m = p.jacobian_transpose.nrows();
    let t = p.transmission.as_ref().map_or(m, |t| t.matrix.ncols());
    p.torque_limits = Some(
        (0..t)
            .map(|j| (j % every == 0).then_some(5.0.into()))
            .collect(),
    );
    let model = Arc::new(GraspModel::new(&p, &ModelOptions::default()).unwrap());
    let qps = [
        TorqueQp::linearized(model.clone(), &p.linearization),
        TorqueQp::exact(model.clone()),
    ];
    (model, qps)
}

/// `|S|` of face row r, force component t, of a contact.
fn face_abs(repr: &ConeRepr, c: &ContactBlock, r: usize, t: usize) -> f64 {
    match repr {
        ConeRepr::Inscribed(cone) => cone.faces[(r, t)].abs(),
        // Exact: the unit normal row (ConeRepr is non-exhaustive).
        _ => (t == c.model.normal_index()) as u8 as f64,
    }
}

#[test]
fn factored_products_match_the_assembled_rows() {
    let files = grasp_testkit::fixture_paths(&["", "hands"]);
    assert!(files.len() >= 9, "{files:?}");
    let mut limited = 0;
    for path in &files {
        let (model, qps) = views(path, 2);
        for qp in qps {
            let ld = qp.least_distance();
            assert!(matches!(ld.h, InequalityRows::Factored(_)));
            let k = qp.joints();
            let x = Matrix::from_fn(k, 7, |i, j| ((3 * i + 5 * j) % 11) as f64 / 7.0 - 0.6);
            let fast = ld.h_mul(&x);
            let plain = qp.h().matmul(&x);
            // Both sum the products s_t z_tl x_lj, in another order: each entry to within
            // the rounding of a sum of m + 4 terms, relative to Σ |s_t| |z_tl| |x_lj|.
            let abs = |a: &Matrix| Matrix::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)].abs());
            let zx = abs(&model.z2).matmul(&abs(&x));
            // Limit rows: ±x exactly.
            let mut size = Matrix::from_fn(plain.nrows(), 7, |i, j| match qp.rows[i] {
                grasp_core::RowId::TorqueLimit { joint, .. } => x[(joint, j)].abs(),
                _ => 0.0,
            });
            for (c, repr) in qp.contacts.iter().zip(&qp.constraints.cones) {
                for r in 0..c.rows {
                    for t in 0..c.model.dim() {
                        let s = face_abs(repr, c, r, t);
                        for j in 0..7 {
                            size[(c.first_row + r, j)] += s * zx[(c.offset + t, j)];
                        }
                    }
                }
            }
            let gamma = 2.0 * (k + 4) as f64 * f64::EPSILON;
            for i in 0..plain.nrows() {
                for j in 0..plain.ncols() {
                    let d = (fast[(i, j)] - plain[(i, j)]).abs();
                    let bound = gamma * size[(i, j)];
                    assert!(d <= bound, "{path:?} row {i} col {j}: {d:e} > {bound:e}");
                }
            }
            limited += qp
                .rows
                .iter()
                .filter(|r| matches!(r, grasp_core::RowId::TorqueLimit { .. }))
                .count();
        }
    }
    assert!(limited > 0);
}

/// `max_i ‖H_i diag(d)‖` from each contact's Gram matrix equals it from the assembled
/// H: the squared norms to within the rounding of their sums, relative to the largest
/// `Σ_l (Σ_t |s_t z_tl| d_l)²`, with column scales over four decades.
#[test]
fn factored_row_norms_match_the_assembled_rows() {
    for path in grasp_testkit::fixture_paths(&["", "hands"]) {
        let (model, qps) = views(&path, 3);
        for qp in qps {
            let k = qp.joints();
            let d: Vec<f64> = (0..k).map(|j| 10f64.powi((j % 5) as i32 - 2)).collect();
            let fast = qp.least_distance().max_row_norm(&d);
            let h = qp.h();
            let sq = |i: usize| -> f64 { (0..k).map(|j| (h[(i, j)] * d[j]).powi(2)).sum() };
            let plain = (0..h.nrows()).map(sq).fold(0.0, f64::max);
            // The size of each squared norm's terms, from |S| |Z2| d.
            let mut size = 0.0f64;
            for (c, repr) in qp.contacts.iter().zip(&qp.constraints.cones) {
                for r in 0..c.rows {
                    let row: f64 = (0..k)
                        .map(|j| {
                            let v: f64 = (0..c.model.dim())
                                .map(|t| {
                                    face_abs(repr, c, r, t) * model.z2[(c.offset + t, j)].abs()
                                })
                                .sum();
                            (v * d[j]).powi(2)
                        })
                        .sum();
                    size = size.max(row);
                }
            }
            size = size.max(plain);
            let gamma = 4.0 * (k + 16) as f64 * f64::EPSILON;
            let diff = (fast * fast - plain).abs();
            assert!(
                diff <= gamma * size,
                "{path:?}: {fast:e}² against {plain:e}, {diff:e} > {:e}",
                gamma * size
            );
        }
    }
}
