//! The figures the page shows and reports: medians over the last frames.

use std::collections::VecDeque;

/// Frames the overlay's and `stats()`'s medians are over.
pub const WINDOW: usize = 60;

/// Appends `v` to `window`, dropping the oldest beyond [`WINDOW`].
pub fn push(window: &mut VecDeque<f64>, v: f64) {
    if window.len() == WINDOW {
        window.pop_front();
    }
    window.push_back(v);
}

/// The median of the finite values in `window`, or None where there are none.
pub fn median(window: &VecDeque<f64>) -> Option<f64> {
    let mut v: Vec<f64> = window.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => None,
        n if n % 2 == 1 => Some(v[n / 2]),
        n => Some(0.5 * (v[n / 2 - 1] + v[n / 2])),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::VecDeque;

    #[test]
    fn the_median_is_of_the_last_window_of_frames() {
        let mut w = VecDeque::new();
        assert_eq!(median(&w), None);
        for v in 0..100 {
            push(&mut w, v as f64);
        }
        assert_eq!(w.len(), WINDOW);
        // The last sixty: 40 … 99.
        assert_eq!(median(&w), Some(69.5));
        push(&mut w, f64::NAN);
        assert_eq!(median(&w), Some(70.0));
    }
}
