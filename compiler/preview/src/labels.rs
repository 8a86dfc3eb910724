//! Where a label goes: the free place nearest the one it asks for, inside its frame and clear
//! of every marker and every label already placed; or nowhere, when the frame has no room.

/// A box on the sheet, px: `[left, top, right, bottom]`.
pub type Rect = [f64; 4];

/// Clear space kept between a label and anything else, px.
const CLEARANCE_PX: f64 = 2.0;
/// The grid the places are tried on, px.
const STEP_PX: f64 = 2.0;

pub fn overlaps(a: &Rect, b: &Rect) -> bool {
    a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3]
}

/// `r` grown by `by` on every side.
pub fn grown(r: &Rect, by: f64) -> Rect {
    [r[0] - by, r[1] - by, r[2] + by, r[3] + by]
}

/// The bounding box of points; `None` when one is not finite or there are none.
pub fn bounds(points: &[[f64; 2]]) -> Option<Rect> {
    let finite = !points.is_empty() && points.iter().flatten().all(|v| v.is_finite());
    finite.then(|| {
        points.iter().fold(
            [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ],
            |b, p| {
                [
                    b[0].min(p[0]),
                    b[1].min(p[1]),
                    b[2].max(p[0]),
                    b[3].max(p[1]),
                ]
            },
        )
    })
}

/// Places labels in frames of one size: the offsets from a wanted place, nearest first.
pub struct Placer {
    offsets: Vec<[f64; 2]>,
}

impl Placer {
    /// For frames `w` × `h` px.
    pub fn new(w: f64, h: f64) -> Placer {
        let (nx, ny) = ((w / STEP_PX).ceil() as i64, (h / STEP_PX).ceil() as i64);
        let mut offsets: Vec<[f64; 2]> = (-nx..=nx)
            .flat_map(|i| (-ny..=ny).map(move |j| [i as f64 * STEP_PX, j as f64 * STEP_PX]))
            .collect();
        // Nearest first; at one distance, above before below, left before right.
        offsets.sort_by(|a, b| {
            (a[0] * a[0] + a[1] * a[1])
                .total_cmp(&(b[0] * b[0] + b[1] * b[1]))
                .then(a[1].total_cmp(&b[1]))
                .then(a[0].total_cmp(&b[0]))
        });
        Placer { offsets }
    }

    /// Where to put a label whose box is `label` about its anchor, wanted at `want`: the
    /// nearest anchor whose box lies inside `frame` and keeps clear of every box of `taken`.
    pub fn place(
        &self,
        frame: &Rect,
        want: [f64; 2],
        label: &Rect,
        taken: &[Rect],
    ) -> Option<[f64; 2]> {
        let inside = grown(frame, -CLEARANCE_PX);
        // The wanted place moved into the frame, so that a label asked for off it is tried
        // from the nearest edge.
        let lo = [inside[0] - label[0], inside[1] - label[1]];
        let hi = [inside[2] - label[2], inside[3] - label[3]];
        if lo[0] > hi[0] || lo[1] > hi[1] {
            return None;
        }
        let start = [want[0].clamp(lo[0], hi[0]), want[1].clamp(lo[1], hi[1])];
        self.offsets.iter().find_map(|d| {
            let at = [start[0] + d[0], start[1] + d[1]];
            let b = [
                label[0] + at[0],
                label[1] + at[1],
                label[2] + at[0],
                label[3] + at[1],
            ];
            let fits =
                b[0] >= inside[0] && b[1] >= inside[1] && b[2] <= inside[2] && b[3] <= inside[3];
            let clear = || taken.iter().all(|t| !overlaps(&grown(t, CLEARANCE_PX), &b));
            (fits && clear()).then_some(at)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_label_takes_the_nearest_free_place_or_none() {
        let p = Placer::new(100.0, 60.0);
        let frame = [0.0, 0.0, 100.0, 60.0];
        let label = [-10.0, -8.0, 10.0, 2.0];
        // Free: where it is wanted.
        assert_eq!(
            p.place(&frame, [50.0, 30.0], &label, &[]),
            Some([50.0, 30.0])
        );
        // A marker there: the nearest place clear of it, above before below.
        let marker = [40.0, 20.0, 60.0, 40.0];
        let at = p.place(&frame, [50.0, 30.0], &label, &[marker]).unwrap();
        let b = [
            label[0] + at[0],
            label[1] + at[1],
            label[2] + at[0],
            label[3] + at[1],
        ];
        assert!(!overlaps(&grown(&marker, CLEARANCE_PX), &b), "{at:?}");
        assert!(at[1] < 30.0, "above: {at:?}");
        // Wanted off the frame: kept inside it.
        let at = p.place(&frame, [150.0, -20.0], &label, &[]).unwrap();
        assert_eq!(at, [100.0 - 2.0 - 10.0, 2.0 + 8.0]);
        // A frame full of marker: nowhere.
        assert_eq!(p.place(&frame, [50.0, 30.0], &label, &[frame]), None);
        // A label larger than the frame: nowhere.
        assert_eq!(
            p.place(&frame, [50.0, 30.0], &[-60.0, -8.0, 60.0, 2.0], &[]),
            None
        );
        assert_eq!(
            bounds(&[[1.0, 5.0], [3.0, -1.0]]),
            Some([1.0, -1.0, 3.0, 5.0])
        );
        assert_eq!(bounds(&[[f64::NAN, 0.0]]), None);
    }
}
