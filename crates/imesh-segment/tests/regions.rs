//! Thin regions of the partition: merging leaves none behind, changes only the merged regions'
//! labels, and keeps every label a label of the image.

use imesh_classify::{LabelGrid, Region};
use imesh_segment::{
    merge_regions, merge_thin_regions, partition, sample, PartitionRegions, SampleOptions,
};
use proptest::prelude::*;

/// Random label images with specks, strips and blobs: a few labels on a coarse random grid,
/// scaled up unevenly so that some regions are one pixel thin and others wide.
fn label_image() -> impl Strategy<Value = LabelGrid> {
    (4u32..40, 4u32..40, 1u32..5)
        .prop_flat_map(|(w, h, labels)| {
            let cells = prop::collection::vec(0..labels, 64);
            (Just((w, h, labels)), cells, 1u32..8, 1u32..8)
        })
        .prop_map(|((w, h, labels), cells, sx, sy)| {
            let grid: Vec<u32> = (0..w * h)
                .map(|i| {
                    let (x, y) = ((i % w) / sx, (i / w) / sy);
                    cells[((y % 8) * 8 + x % 8) as usize]
                })
                .collect();
            let regions = (0..labels)
                .map(|l| Region {
                    name: format!("l{l}"),
                    colour: [l as u8; 3],
                })
                .collect();
            LabelGrid::new(w, h, grid, regions).unwrap()
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn no_thin_region_is_left_and_only_merged_ones_change(
        grid in label_image(),
        min_width in 0.3..4.0f64,
    ) {
        let sampling = sample(&grid, &SampleOptions::default()).unwrap();
        let t = &sampling.triangulation;
        let before = partition(&grid, t);
        let regions_before = PartitionRegions::new(t, &before);
        let mut after = before.clone();
        let report = merge_thin_regions(t, &mut after, min_width);
        let regions_after = PartitionRegions::new(t, &after);
        // None thinner than asked, unless it is the whole domain.
        if regions_after.regions.len() > 1 {
            for r in &regions_after.regions {
                prop_assert!(r.width() >= min_width, "a region of width {} is left", r.width());
            }
        }
        // Each merge joins two regions (or more, when it connects regions of one label).
        prop_assert!(regions_after.regions.len() + report.regions <= regions_before.regions.len());
        // Only triangles of merged regions change, to a label the image has.
        let changed: f64 = t
            .triangles()
            .filter(|f| before[f.index()] != after[f.index()])
            .map(|f| t.signed_area(f).abs())
            .sum();
        prop_assert!(changed <= report.area * (1.0 + 1e-9) + 1e-9);
        prop_assert_eq!(report.regions == 0, changed == 0.0 && report.area == 0.0);
        for f in t.triangles() {
            prop_assert!((after[f.index()] as usize) < grid.regions().len());
        }
        // The total area is the domain's.
        let total: f64 = regions_after.regions.iter().map(|r| r.area).sum();
        let domain = f64::from(grid.width()) * f64::from(grid.height());
        prop_assert!((total - domain).abs() <= 1e-9 * domain);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Every region named by a triangle is merged away (its triangles end in a larger region),
    /// whatever its width, and no region thinner than asked is left.
    #[test]
    fn named_regions_are_merged_whatever_their_width(
        grid in label_image(),
        min_width in 0.0..2.0f64,
        picks in prop::collection::vec(any::<prop::sample::Index>(), 1..4),
    ) {
        let sampling = sample(&grid, &SampleOptions::default()).unwrap();
        let t = &sampling.triangulation;
        let before = partition(&grid, t);
        let regions_before = PartitionRegions::new(t, &before);
        let triangles: Vec<_> = t.triangles().collect();
        let named: Vec<_> = picks.iter().map(|i| *i.get(&triangles)).collect();
        let mut after = before.clone();
        let report = merge_regions(t, &mut after, min_width, &named);
        let regions_after = PartitionRegions::new(t, &after);
        if regions_before.regions.len() == 1 {
            prop_assert_eq!(report.regions, 0);
            prop_assert_eq!(&after, &before);
        } else {
            for f in &named {
                let old = &regions_before.regions[regions_before.of_triangle[f.index()] as usize];
                let new = &regions_after.regions[regions_after.of_triangle[f.index()] as usize];
                prop_assert!(new.area > old.area, "a named region was kept");
            }
            if regions_after.regions.len() > 1 {
                prop_assert!(regions_after.regions.iter().all(|r| r.width() >= min_width));
            }
        }
        prop_assert!(regions_after.regions.len() + report.regions <= regions_before.regions.len());
    }
}

/// Nothing changes at a width of 0, and regions wider than asked are kept.
#[test]
fn wide_regions_are_kept() {
    // Two halves of a 20 × 10 image.
    let labels = (0..200).map(|i| u32::from(i % 20 >= 10)).collect();
    let regions = vec![
        Region {
            name: "a".into(),
            colour: [0; 3],
        },
        Region {
            name: "b".into(),
            colour: [255; 3],
        },
    ];
    let grid = LabelGrid::new(20, 10, labels, regions).unwrap();
    let sampling = sample(&grid, &SampleOptions::default()).unwrap();
    let t = &sampling.triangulation;
    let before = partition(&grid, t);
    for min_width in [0.0, 1.0, 2.0] {
        let mut after = before.clone();
        let report = merge_thin_regions(t, &mut after, min_width);
        assert_eq!(report.regions, 0);
        assert_eq!(after, before);
    }
    // Each half is 10 × 10 (width 2·100/40 = 5): merged at 6, into one region.
    let mut after = before.clone();
    let report = merge_thin_regions(t, &mut after, 6.0);
    assert_eq!(report.regions, 1);
    assert_eq!(PartitionRegions::new(t, &after).regions.len(), 1);
}
