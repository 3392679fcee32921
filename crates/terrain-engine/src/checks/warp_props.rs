//! Property tests of the warp over random importance maps (proptest).

use proptest::prelude::*;
use terrain_engine::scene::WarpMethod;
use terrain_engine::stage::lines::{LineScratch, line_mapping};
use terrain_engine::stage::warp::{Warp, pair_unfolded};

/// Importance maps of side 2..48 with values log-uniform over 1e-6..1e6.
fn importance_map() -> impl Strategy<Value = (usize, Vec<f32>)> {
    (2usize..48).prop_flat_map(|n| {
        (
            Just(n),
            prop::collection::vec((-6.0f32..6.0).prop_map(|e| 10f32.powf(e)), n * n),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn line_mapping_is_monotone_and_keeps_its_ends(imp in prop::collection::vec((-6.0f32..6.0).prop_map(|e| 10f32.powf(e)), 2..300)) {
        let n = imp.len();
        let mut out = vec![0.0; n];
        line_mapping(&imp, &mut LineScratch::new(n), &mut out);
        prop_assert_eq!(out[0], 0.0);
        prop_assert_eq!(out[n - 1], (n - 1) as f64);
        for w in out.windows(2) {
            prop_assert!(w[1] > w[0], "not increasing: {:?}", w);
        }
    }

    #[test]
    fn uniform_importance_is_the_identity(n in 2usize..64, v in (-6.0f32..6.0).prop_map(|e| 10f32.powf(e)), d0 in 0.01f32..1000.0) {
        for method in [WarpMethod::Plain, WarpMethod::Guarded] {
            let mut w = Warp::new(n, method, 0.0);
            w.run(&vec![v; n * n], d0);
            for t in 0..n {
                for s in 0..n {
                    let p = w.phi[t * n + s];
                    let tol = 1e-4 * d0 * n as f32;
                    prop_assert!((p[0] - s as f32 * d0).abs() <= tol && (p[1] - t as f32 * d0).abs() <= tol,
                        "Φ({}, {}) = {:?}", s, t, p);
                }
            }
        }
    }

    #[test]
    fn warp_stays_in_the_region_keeps_corners_and_edges((n, imp) in importance_map(), d0 in 0.01f32..1000.0) {
        for method in [WarpMethod::Plain, WarpMethod::Guarded] {
            let mut w = Warp::new(n, method, 0.0);
            w.run(&imp, d0);
            let extent = (n - 1) as f32 * d0;
            let tol = 1e-5 * extent;
            for p in &w.phi {
                prop_assert!(p[0] >= -tol && p[0] <= extent + tol && p[1] >= -tol && p[1] <= extent + tol, "{:?}", p);
            }
            for k in 0..n {
                prop_assert!(w.phi[k * n][0].abs() <= tol && (w.phi[k * n + n - 1][0] - extent).abs() <= tol);
                prop_assert!(w.phi[k][1].abs() <= tol && (w.phi[(n - 1) * n + k][1] - extent).abs() <= tol);
            }
            // Columns increase in y with either method; the plain warp may fold across them.
            for s in 0..n {
                for t in 0..n - 1 {
                    prop_assert!(w.phi[(t + 1) * n + s][1] > w.phi[t * n + s][1]);
                }
            }
        }
    }

    #[test]
    fn guarded_warp_never_folds_and_rows_increase((n, imp) in importance_map(), d0 in 0.01f32..1000.0) {
        // Rows first (the paper's order) and columns first (`run_across`, views along x).
        for across in [false, true] {
            let mut w = Warp::new(n, WarpMethod::Guarded, 0.0);
            if across {
                w.run_across(&imp, d0);
            } else {
                w.run(&imp, d0);
            }
            for s in 0..n - 1 {
                prop_assert!(pair_unfolded(&w.phi, n, s), "fold between columns {} and {} (across: {})", s, s + 1, across);
            }
            let extent = (n - 1) as f32 * d0;
            let tol = 1e-5 * extent;
            for k in 0..n {
                prop_assert!(w.phi[k * n][0].abs() <= tol && (w.phi[k * n + n - 1][0] - extent).abs() <= tol);
                prop_assert!(w.phi[k][1].abs() <= tol && (w.phi[(n - 1) * n + k][1] - extent).abs() <= tol);
            }
            for t in 0..n {
                for s in 0..n - 1 {
                    prop_assert!(w.phi[t * n + s + 1][0] > w.phi[t * n + s][0]);
                    prop_assert!(w.phi[(s + 1) * n + t][1] > w.phi[s * n + t][1]);
                }
            }
        }
    }

    /// Columns first is rows first on the map transposed, Φ reflected back across the diagonal.
    #[test]
    fn the_warp_across_is_the_warp_of_the_transposed_map((n, imp) in importance_map(), d0 in 0.01f32..1000.0) {
        let transposed: Vec<f32> = (0..n * n).map(|k| imp[(k % n) * n + k / n]).collect();
        let (mut a, mut b) = (Warp::new(n, WarpMethod::Guarded, 0.0), Warp::new(n, WarpMethod::Guarded, 0.0));
        a.run_across(&imp, d0);
        b.run(&transposed, d0);
        for t in 0..n {
            for s in 0..n {
                let (p, q) = (a.phi[t * n + s], b.phi[s * n + t]);
                prop_assert_eq!(p, [q[1], q[0]], "Φ({}, {})", s, t);
            }
        }
    }
}
