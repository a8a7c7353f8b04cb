//! The Pareto front of cost against error: the variants no other variant beats on both.

/// For each point `(cost, error)`, whether it is on the front: no other point has a cost and an
/// error at most its own with one of them strictly smaller. Points with a non-finite coordinate are
/// never on it (nor do they dominate).
pub fn front(points: &[(f64, f64)]) -> Vec<bool> {
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    points
        .iter()
        .map(|p| {
            finite(p)
                && !points
                    .iter()
                    .any(|q| finite(q) && q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::front;

    #[test]
    fn dominated_points_are_off_the_front() {
        let points = [(1.0, 10.0), (2.0, 5.0), (3.0, 6.0), (4.0, 1.0), (2.0, 5.0)];
        assert_eq!(front(&points), [true, true, false, true, true]);
        assert_eq!(front(&[(1.0, f64::NAN), (2.0, 1.0)]), [false, true]);
    }
}
