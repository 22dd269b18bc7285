//! `--colors N` for `original` and `pastel`: N of the model's own colours, chosen in Oklab by a weighted
//! k-means. Seeds are picked deterministically, each the colour farthest from the seeds before it with its
//! distance weighted by only 1 + the logarithm of its cell count, so a small patch of a distinct colour (a
//! bright eye, a red button) gets a centre of its own rather than being averaged into a large neighbour;
//! each final centre is then replaced by the model colour nearest it, so the result shows colours the model
//! has.

use super::oklab::{self, Lab};

/// Lloyd iterations after seeding (the centres of voxel models' few thousand colours settle in a handful).
const ITERATIONS: usize = 8;

/// At most `n` (≥ 1) colours of `histogram` (distinct colours with their cell counts, in a fixed order) that
/// stand for all of them: all of them when they are `n` or fewer.
pub(super) fn representatives(histogram: &[([u8; 3], usize)], n: usize) -> Vec<[u8; 3]> {
    if histogram.len() <= n {
        return histogram.iter().map(|&(c, _)| c).collect();
    }
    let labs: Vec<Lab> = histogram.iter().map(|&(c, _)| oklab::from_srgb(c)).collect();
    let weights: Vec<f32> = histogram.iter().map(|&(_, w)| w as f32).collect();
    let mut centres = seeds(&labs, &weights, n);
    let mut nearest = vec![0; labs.len()];
    for _ in 0..ITERATIONS {
        for (slot, lab) in nearest.iter_mut().zip(&labs) {
            *slot = oklab::nearest(&centres, lab);
        }
        let mut sums = vec![([0.0f64; 3], 0.0f64); centres.len()];
        for ((lab, &w), &k) in labs.iter().zip(&weights).zip(&nearest) {
            for (sum, &c) in sums[k].0.iter_mut().zip(lab) {
                *sum += f64::from(c) * f64::from(w);
            }
            sums[k].1 += f64::from(w);
        }
        for (centre, (sum, total)) in centres.iter_mut().zip(sums) {
            if total > 0.0 {
                *centre = sum.map(|s| (s / total) as f32);
            }
        }
    }
    // Each centre becomes the nearest model colour; two centres may land on one.
    let mut chosen: Vec<usize> = centres.iter().map(|c| oklab::nearest(&labs, c)).collect();
    chosen.sort_unstable();
    chosen.dedup();
    chosen.into_iter().map(|i| histogram[i].0).collect()
}

/// `n` seeds: the most used colour, then each time the colour with the largest squared distance to its
/// nearest seed × (1 + ln(its count)) (the first of equals); fewer when every colour is a seed's.
fn seeds(labs: &[Lab], weights: &[f32], n: usize) -> Vec<Lab> {
    let first = (0..labs.len()).fold(0, |best, i| if weights[i] > weights[best] { i } else { best });
    let mut centres = vec![labs[first]];
    let mut distance: Vec<f32> = labs.iter().map(|lab| oklab::distance2(lab, &labs[first])).collect();
    while centres.len() < n {
        let score = |i: usize| distance[i] * (1.0 + weights[i].ln());
        let next = (0..labs.len()).fold(0, |best, i| if score(i) > score(best) { i } else { best });
        if score(next) <= 0.0 {
            break;
        }
        centres.push(labs[next]);
        for (d, lab) in distance.iter_mut().zip(labs) {
            *d = d.min(oklab::distance2(lab, &labs[next]));
        }
    }
    centres
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn few_colors_are_all_kept() {
        let h = [([1, 2, 3], 4), ([9, 9, 9], 1)];
        assert_eq!(representatives(&h, 2), [[1, 2, 3], [9, 9, 9]]);
    }

    #[test]
    fn a_small_bright_patch_keeps_its_color_among_many_greens() {
        // 400 greens (a gradient, 50 cells each) and 12 cells of a bright red.
        let mut h: Vec<([u8; 3], usize)> =
            (0..400).map(|i| ([20 + (i % 20) as u8, 100 + (i / 20) as u8 * 5, 30], 50)).collect();
        h.push(([250, 20, 40], 12));
        for n in [2, 4, 8] {
            let chosen = representatives(&h, n);
            assert_eq!(chosen.len(), n);
            assert!(chosen.contains(&[250, 20, 40]), "{n}: {chosen:?}");
            assert!(chosen.iter().all(|c| h.iter().any(|(m, _)| m == c)), "model colours only");
        }
        assert_eq!(representatives(&h, 8), representatives(&h, 8), "deterministic");
    }
}
