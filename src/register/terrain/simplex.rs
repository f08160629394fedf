//! Nelder-Mead maximisation (the standard reflection / expansion / contraction / shrink
//! coefficients 1, 2, ½, ½) for the derivative-free alignment scores.

/// The best point found and its value after at most `max_evals` evaluations of `f`, from an
/// axis-aligned start simplex of side `step` around `x0`; stops when the simplex's values
/// span less than `ftol` and its points lie within `xtol` of the best (both absolute).
pub fn maximise(
    f: &mut dyn FnMut(&[f64]) -> f64,
    x0: &[f64],
    step: f64,
    xtol: f64,
    ftol: f64,
    max_evals: usize,
) -> (Vec<f64>, f64, usize) {
    let n = x0.len();
    if n == 0 {
        return (Vec::new(), f(x0), 1);
    }
    let mut pts: Vec<Vec<f64>> = vec![x0.to_vec()];
    for i in 0..n {
        let mut p = x0.to_vec();
        p[i] += step;
        pts.push(p);
    }
    let mut vals: Vec<f64> = pts.iter().map(|p| f(p)).collect();
    let mut evals = n + 1;
    let lerp = |a: &[f64], b: &[f64], t: f64| -> Vec<f64> {
        a.iter().zip(b).map(|(x, y)| x + t * (y - x)).collect()
    };
    while evals < max_evals {
        // Order best (highest) first; ties keep their order, so the run is deterministic.
        let mut order: Vec<usize> = (0..=n).collect();
        order.sort_by(|&a, &b| vals[b].total_cmp(&vals[a]));
        pts = order.iter().map(|&i| pts[i].clone()).collect();
        vals = order.iter().map(|&i| vals[i]).collect();
        let spread_x = pts[1..]
            .iter()
            .map(|p| {
                p.iter()
                    .zip(&pts[0])
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        if vals[0] - vals[n] <= ftol && spread_x <= xtol {
            break;
        }
        let centroid: Vec<f64> = (0..n)
            .map(|k| pts[..n].iter().map(|p| p[k]).sum::<f64>() / n as f64)
            .collect();
        let worst = pts[n].clone();
        let xr = lerp(&centroid, &worst, -1.0);
        let fr = f(&xr);
        evals += 1;
        if fr > vals[0] {
            let xe = lerp(&centroid, &worst, -2.0);
            let fe = f(&xe);
            evals += 1;
            (pts[n], vals[n]) = if fe > fr { (xe, fe) } else { (xr, fr) };
        } else if fr > vals[n - 1] {
            (pts[n], vals[n]) = (xr, fr);
        } else {
            let (xc, fc) = if fr > vals[n] {
                let xc = lerp(&centroid, &xr, 0.5);
                let fc = f(&xc);
                (xc, fc)
            } else {
                let xc = lerp(&centroid, &worst, 0.5);
                let fc = f(&xc);
                (xc, fc)
            };
            evals += 1;
            if fc > vals[n].max(fr) {
                (pts[n], vals[n]) = (xc, fc);
            } else {
                for i in 1..=n {
                    pts[i] = lerp(&pts[0], &pts[i], 0.5);
                    vals[i] = f(&pts[i]);
                }
                evals += n;
            }
        }
    }
    let best = (0..=n)
        .max_by(|&a, &b| vals[a].total_cmp(&vals[b]).then(b.cmp(&a)))
        .unwrap_or(0);
    (pts[best].clone(), vals[best], evals)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_peak_of_a_tilted_quadratic() {
        let mut f = |x: &[f64]| {
            -((x[0] - 1.0).powi(2)
                + 10.0 * (x[1] + 2.0 - 0.5 * x[0]).powi(2)
                + (x[2] - 0.3).powi(2))
        };
        let (x, v, evals) = maximise(&mut f, &[0.0, 0.0, 0.0], 1.0, 1e-7, 1e-12, 5000);
        assert!(
            (x[0] - 1.0).abs() < 1e-4 && (x[1] + 1.5).abs() < 1e-4 && (x[2] - 0.3).abs() < 1e-4,
            "{x:?} {v} {evals}"
        );
    }
}
