//! The fast grid paths classify every point exactly as the straightforward
//! KD-tree implementations do, on crops of realistic simulated frames
//! (noise, dropouts, mixed pixels, bevels, shadows), for both methods, and
//! cluster the plane points exactly as the per-pixel union-find does: on
//! every instruction set level this CPU runs, forced in turn; and the
//! full count's memo keys of every level equal the scalar key.

use crate::camera::CameraModel;
use crate::geometry::Vec3;
use crate::joint::JointType;
use crate::kernels::exactness::{agree_with_scalar, crop};
use crate::kernels::{self, BLOCK, on_every_isa};
use crate::pipeline::clustering;
use crate::pipeline::edge_points::{self, EdgeCriterion, FullCount, Plate};
use crate::pipeline::neighbours::{FULL_COUNT_TILE_PX, FullCounts, NeighbourSearch};
use crate::pipeline::orientation::dominant_normal;
use crate::pipeline::plane_points::{self, RobustPlaneCriterion};

#[test]
fn plane_and_edge_criteria_match_the_kdtree_reference_point_for_point() {
    let camera = CameraModel::default();
    for (joint, distance, tilt) in
        [(JointType::VButt, 500.0, 20.0), (JointType::IButt, 760.0, 5.0), (JointType::Lap, 980.0, 28.0)]
    {
        let cloud = crop(joint, distance, tilt, 360, 240);
        let grid = NeighbourSearch::new(&cloud, &camera, 1.0);
        let tree = NeighbourSearch::kdtree(&cloud, &camera, 1.0);
        let normal = dominant_normal(&cloud, &grid, camera.fx(), 5.0).unwrap_or_else(Vec3::z);
        let criterion = RobustPlaneCriterion { normal, min_ratio: 0.8, max_angle_deg: 20.0 };

        let robust_expected = plane_points::reference(&tree, false, &criterion);
        let paper_expected = plane_points::reference(&tree, true, &criterion);
        on_every_isa(|isa| {
            let robust = plane_points::robust_criterion(&grid, &criterion);
            assert_eq!(robust.mask, robust_expected, "{joint} robust plane points on {isa:?}");
            let paper = plane_points::paper_criterion(&cloud, &camera, &grid);
            assert_eq!(paper.mask, paper_expected, "{joint} paper plane points on {isa:?}");

            for (plane, edge) in [
                (&robust, EdgeCriterion { full: FullCount::Plane, ratio: 0.75 }),
                (&paper, EdgeCriterion { full: FullCount::Frontal, ratio: 0.5 }),
            ] {
                // One plate: the plane points themselves, labelled 0.
                let labels: Vec<u32> = plane.mask.iter().map(|&m| if m { 0 } else { u32::MAX }).collect();
                let members: Vec<u32> = (0..cloud.len() as u32).filter(|&i| plane.mask[i as usize]).collect();
                let plate = Plate { labels: &labels, label: 0, members: &members };
                let mut fast = edge_points::edge_points(&grid, plane, plate, &edge);
                fast.sort_unstable();
                assert_eq!(fast, edge_points::reference(&tree, plane, plate, &edge), "{joint} edge points on {isa:?}");
                assert!(!fast.is_empty(), "{joint}: the crop holds edges");
            }
        });
    }
}

#[test]
fn grid_clustering_matches_the_per_pixel_reference() {
    let camera = CameraModel::default();
    let pools: Vec<_> = [1, 3].map(|n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap()).into();
    for (joint, distance, tilt) in
        [(JointType::VButt, 620.0, 12.0), (JointType::IButt, 500.0, 10.0), (JointType::Lap, 900.0, 25.0)]
    {
        let cloud = crop(joint, distance, tilt, 400, 300);
        let grid = NeighbourSearch::new(&cloud, &camera, 1.0);
        let normal = dominant_normal(&cloud, &grid, camera.fx(), 5.0).unwrap_or_else(Vec3::z);
        let criterion = RobustPlaneCriterion { normal, min_ratio: 0.8, max_angle_deg: 20.0 };
        let mask = plane_points::robust_criterion(&grid, &criterion).mask;
        for (tolerance, min_points) in [(1.0, 30), (0.3, 1)] {
            let expected = clustering::reference(&cloud, &mask, tolerance, min_points);
            assert!(expected.members.len() >= 2, "{joint}: the crop holds more than one cluster");
            on_every_isa(|isa| {
                for pool in &pools {
                    let got = pool.install(|| clustering::grid(&cloud, &mask, tolerance, min_points));
                    let what = format!("{joint}, {tolerance} mm, {} threads, {isa:?}", pool.current_num_threads());
                    assert!(got.labels == expected.labels, "{what}: labels differ");
                    assert_eq!(got.members, expected.members, "{what}: members");
                }
            });
        }
    }
}

#[test]
fn both_plates_in_one_pass_match_the_kdtree_reference_in_order() {
    let camera = CameraModel::default();
    let (w, h) = (300, 200);
    let cloud = crop(JointType::IButt, 560.0, 12.0, w, h);
    let grid = NeighbourSearch::new(&cloud, &camera, 1.0);
    let tree = NeighbourSearch::kdtree(&cloud, &camera, 1.0);
    let normal = dominant_normal(&cloud, &grid, camera.fx(), 5.0).unwrap_or_else(Vec3::z);
    let plane =
        plane_points::robust_criterion(&grid, &RobustPlaneCriterion { normal, min_ratio: 0.8, max_angle_deg: 20.0 });
    // Two plates meeting along a slanted line, with a third label between
    // them, and small islands of each inside the other: an island's
    // windows hold mostly the other plate, so mixing up the plates'
    // member counts would skip its edges.
    let labels: Vec<u32> = (0..cloud.len())
        .map(|i| {
            let (col, row) = (i % w, i / w);
            let island = col % 25 < 3 && row % 25 < 3;
            match (plane.mask[i], (col + row / 3) % 160, island) {
                (false, _, _) => u32::MAX,
                (true, 75..80, _) => 2,
                (true, 0..75, false) | (true, 80.., true) => 7,
                (true, _, _) => 4,
            }
        })
        .collect();
    let members =
        |label: u32| -> Vec<u32> { (0..cloud.len() as u32).filter(|&i| labels[i as usize] == label).collect() };
    let (a, b) = (members(7), members(4));
    let plates = [Plate { labels: &labels, label: 7, members: &a }, Plate { labels: &labels, label: 4, members: &b }];
    for criterion in
        [EdgeCriterion { full: FullCount::Plane, ratio: 0.75 }, EdgeCriterion { full: FullCount::Frontal, ratio: 0.5 }]
    {
        let expected = plates.map(|plate| edge_points::reference(&tree, &plane, plate, &criterion));
        on_every_isa(|isa| {
            let both = edge_points::edge_points_of_plates(&grid, &plane, plates, &criterion);
            for (k, plate) in plates.into_iter().enumerate() {
                assert_eq!(both[k], expected[k], "plate {k} on {isa:?}");
                let alone = edge_points::edge_points(&grid, &plane, plate, &criterion);
                assert_eq!(both[k], alone, "plate {k} alone on {isa:?}");
                assert!(both[k].len() > 50, "plate {k} has edges along the split");
            }
        });
    }
}

#[test]
fn the_memo_keys_of_every_level_equal_the_scalar_key() {
    let camera = CameraModel::default();
    let cloud = crop(JointType::IButt, 500.0, 10.0, 16, 8);
    let search = NeighbourSearch::new(&cloud, &camera, 1.0);
    let scales = FullCounts::new(&search, &Vec3::z()).scales();
    // Depths on and around the half-millimetre steps, tile borders in
    // x / z, and the values the floor clamps.
    let mut values = vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, -0.0, 1.0e30, -1.0e30, 1.0e-30];
    for k in 0..400 {
        let z = 480.0 + k as f32 * 0.125;
        values.extend([z, f32::from_bits(z.to_bits() + 1), f32::from_bits(z.to_bits() - 1)]);
    }
    let depths: Vec<f32> = values.iter().map(|v| v.abs().max(100.0)).chain(values.iter().copied()).collect();
    let tile = (FULL_COUNT_TILE_PX as f64 / camera.fx()) as f32;
    let blocks: Vec<[[f32; BLOCK]; 3]> = depths
        .chunks_exact(BLOCK)
        .enumerate()
        .map(|(chunk, zs)| {
            let zs: [f32; BLOCK] = zs.try_into().unwrap();
            let xs = std::array::from_fn(|l| (chunk as f32 - 200.0 + l as f32 * 0.3) * tile * zs[l] / 7.0);
            let ys = std::array::from_fn(|l| values[(chunk * 3 + l) % values.len()]);
            [xs, ys, zs]
        })
        .collect();
    assert!(blocks.len() * BLOCK > 2000);
    let keys =
        agree_with_scalar("memo keys", || blocks.iter().map(|lanes| kernels::tile_keys(lanes, &scales)).collect());
    for (lanes, keys) in blocks.iter().zip(&keys) {
        for l in 0..BLOCK {
            let p = [lanes[0][l], lanes[1][l], lanes[2][l]];
            assert_eq!(keys[l], kernels::tile_key(&p, &scales), "lane {l} of {p:?}");
        }
    }
}
