//! Order statistics of measured times, which the jobs (`fly`) and the evaluation (`compare`)
//! report alike.

/// The `q` quantile of `v` (not empty) by nearest rank: the value at `⌊len·q⌋` in order, so
/// that the median of an odd count is its middle value, and each quartile of 15 frames has three
/// frames beyond it.
pub fn percentile(v: &[f64], q: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[((s.len() as f64 * q) as usize).min(s.len() - 1)]
}
