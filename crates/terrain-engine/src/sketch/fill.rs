//! Filling nodata: each missing cell takes the mean of its already-valid 8-neighbours, in rings
//! outward from the valid data (a breadth-first front), so holes close smoothly from their rims.
//!
//! A ring is finished before the next begins, which makes the result independent of scan order.
//! Rejected alternative: repeated whole-grid diffusion passes; a half-empty 4097² grid would need
//! thousands of passes, the front touches each cell a constant number of times.

/// Replaces every non-finite value; returns how many there were. A grid with no valid cell becomes 0.
pub fn fill_nodata(data: &mut [f32], width: usize, height: usize) -> usize {
    let missing = data.iter().filter(|h| !h.is_finite()).count();
    if missing == 0 {
        return 0;
    }
    if missing == data.len() {
        data.fill(0.0);
        return missing;
    }
    let mut valid: Vec<bool> = data.iter().map(|h| h.is_finite()).collect();
    let neighbours = |k: usize| {
        let (i, j) = ((k % width) as isize, (k / width) as isize);
        (-1isize..=1)
            .flat_map(move |dj| (-1isize..=1).map(move |di| (i + di, j + dj)))
            .filter(move |&(x, y)| {
                (x, y) != (i, j) && x >= 0 && y >= 0 && x < width as isize && y < height as isize
            })
            .map(move |(x, y)| y as usize * width + x as usize)
    };
    let mut queued = valid.clone();
    let mut ring: Vec<usize> = Vec::new();
    for k in 0..data.len() {
        if !valid[k] && neighbours(k).any(|n| valid[n]) {
            ring.push(k);
            queued[k] = true;
        }
    }
    let mut values = Vec::new();
    while !ring.is_empty() {
        values.clear();
        for &k in &ring {
            let (sum, count) = neighbours(k)
                .filter(|&n| valid[n])
                .fold((0.0f64, 0u32), |(s, c), n| (s + data[n] as f64, c + 1));
            values.push((sum / count as f64) as f32);
        }
        for (&k, &v) in ring.iter().zip(&values) {
            data[k] = v;
            valid[k] = true;
        }
        let mut next = Vec::new();
        for &k in &ring {
            for n in neighbours(k) {
                if !queued[n] {
                    queued[n] = true;
                    next.push(n);
                }
            }
        }
        ring = next;
    }
    missing
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hole_takes_its_rim_and_is_counted() {
        let mut d = vec![5.0; 25];
        d[12] = f32::NAN;
        d[13] = f32::NAN;
        assert_eq!(fill_nodata(&mut d, 5, 5), 2);
        assert!(d.iter().all(|&h| h == 5.0));
    }

    #[test]
    fn half_empty_grid_fills_with_values_from_the_valid_half() {
        let (w, h) = (64, 64);
        let mut d: Vec<f32> = (0..w * h)
            .map(|k| if k % w < 32 { (k / w) as f32 } else { f32::NAN })
            .collect();
        assert_eq!(fill_nodata(&mut d, w, h), w * h / 2);
        assert!(d.iter().all(|v| v.is_finite() && (0.0..64.0).contains(v)));
    }

    #[test]
    fn all_nodata_becomes_sea_level() {
        let mut d = vec![f32::NAN; 16];
        assert_eq!(fill_nodata(&mut d, 4, 4), 16);
        assert!(d.iter().all(|&h| h == 0.0));
    }
}
