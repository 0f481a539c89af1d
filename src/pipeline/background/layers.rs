//! The robust rule ([`robust_select`]): the facing clusters sorted into
//! layers along the workpiece's normal, and the butt pair, the lap's two
//! layers or the tee's web over its flange found in them, or why not.

use crate::cloud::Point;
use crate::geometry::Vec3;
use crate::joint::JointType;

use super::super::workpieces::MAX_JOINT_OPENING_MM;
use super::beside::standing_beside;
use super::image_break;
use super::placement::{
    BAR_ELONGATION, FALL_MIN_POINTS, SIDE_BY_SIDE_AREA_RATIO, face_falls_from, lies_across, lies_between_pair,
    lies_beyond_pair, seen_beside, side_of, spacing_of,
};
use super::{BackgroundError, Layout, PlaneCluster, Selected, Selection, Workpiece};

/// The clusters sorted into layers along the normal, nearest the camera
/// first, each layer's clusters largest first.
struct Layers {
    layers: Vec<Vec<PlaneCluster>>,
    normal: Vec3,
    found: usize,
    offsets_mm: Vec<f64>,
}

impl Layers {
    fn offset(&self, c: &PlaneCluster) -> f64 {
        self.normal.dot(&c.centroid)
    }

    /// The offset of layer `k`'s largest cluster.
    fn depth(&self, k: usize) -> f64 {
        self.offset(&self.layers[k][0])
    }

    /// How far behind layer `k` the next layer lies, if there is one.
    fn depth_behind(&self, k: usize) -> Option<f64> {
        (k + 1 < self.layers.len()).then(|| self.depth(k + 1) - self.depth(k))
    }
}

/// Where a butt joint's plates are: the layer holding them.
fn find_butt(l: &Layers, s: &Selection, joint: JointType) -> Result<usize, BackgroundError> {
    let Some(pos) = l.layers.iter().position(|layer| layer.len() >= 2) else {
        // Say what the layers look like when they look like a lap.
        if l.layers.len() >= 2 {
            let step_mm = l.depth(1) - l.depth(0);
            if (s.lap_step_min_mm..=s.lap_step_max_mm).contains(&step_mm) {
                return Err(BackgroundError::LooksLikeLap { joint, step_mm });
            }
        }
        return Err(BackgroundError::NoCoplanarPair { found: l.found, offsets_mm: l.offsets_mm.clone() });
    };
    // The plates are the workpiece's top: a nearer plane may be a clamp,
    // but not one larger than a plate. One lying across the pair (a clamp,
    // or a tee's web on its flange) stands between the pair's edges, where
    // the groove probe sees it and says which.
    let smaller_mm2 = l.layers[pos][1].area_mm2;
    if let Some(cover) = l.layers[..pos].iter().map(|layer| &layer[0]).find(|c| c.area_mm2 > smaller_mm2) {
        return Err(BackgroundError::PairUnderLargerPlane {
            area_mm2: cover.area_mm2,
            above_mm: l.depth(pos) - l.offset(cover),
            smaller_mm2,
        });
    }
    let [first, second, rest @ ..] = l.layers[pos].as_slice() else { return Ok(pos) };
    if let Some(third) = rest
        .iter()
        .find(|c| c.area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * smaller_mm2 && lies_beyond_pair(first, second, c, &l.normal))
    {
        return Err(BackgroundError::ThreeSideBySide {
            joint,
            first_mm2: first.area_mm2,
            second_mm2: second.area_mm2,
            third_mm2: third.area_mm2,
        });
    }
    Ok(pos)
}

/// A tee's web top over its flange: the top's place in the layers, the
/// flange's layer, and the largest flange piece on each side of the web
/// (the side `normal × long axis` points to second), None on a side where
/// no piece is seen; and whether the top was taken for a web's by the
/// faces falling from it rather than by its shape (a block's top, wider
/// than a web is thick).
#[derive(Debug, Clone, Copy, PartialEq)]
struct TeeLayers {
    top: (usize, usize),
    flange: usize,
    sides: [Option<usize>; 2],
    by_faces: bool,
}

impl TeeLayers {
    fn two_sided(&self) -> bool {
        self.sides.iter().all(Option::is_some)
    }

    fn top<'l>(&self, l: &'l Layers) -> &'l PlaneCluster {
        &l.layers[self.top.0][self.top.1]
    }

    fn height(&self, l: &Layers) -> f64 {
        l.depth(self.flange) - l.offset(self.top(l))
    }

    fn piece_mm2(&self, l: &Layers, side: usize) -> f64 {
        self.sides[side].map_or(0.0, |k| l.layers[self.flange][k].area_mm2)
    }
}

/// Where a tee is: the nearest long narrow plane, the largest of its layer
/// (butt plates lie side by side; a sliver of plate beside a larger one is
/// no web), at most a web's thickness wide, whose nearest lower layer lies
/// a web's height under it ([`stands_as_web`]: more than a lap's step, or
/// under a tee's request standing taller than its top is wide, as no bar
/// or clamp lying on a plate does) and holds a plane beside it, with no
/// larger plane nearer the camera (a V-groove's root land under its plates
/// is narrow and long too). A web seen over its flange on both sides
/// first; else one over a plane on one side.
///
/// Where no such plane is found and a tee may be what the request names
/// (`t_fillet`, or no type given), a wider or squarer top is a web's by
/// its faces: one standing more than a lap's step over the plane beside
/// it, seen on both of its sides, with a face falling from its edges to
/// that plane ([`super::placement::face_falls_from`]), as a block standing
/// on a plate shows. A member stands on a plate whatever the width of its top; a
/// lap's upper plate stands no higher than a lap step, and a plate held
/// over another shows no face between them.
fn find_tee(l: &Layers, s: &Selection, points: &[Point]) -> Option<TeeLayers> {
    let narrow = |top: &PlaneCluster| top.elongation >= BAR_ELONGATION && top.width_mm() <= s.web_thickness_max_mm;
    let found = find_tee_by(l, s, points, |top, _| narrow(top).then_some(false));
    if found.is_some() || !matches!(s.joint, None | Some(JointType::TFillet)) {
        return found;
    }
    // Only over the plane seen on both of its sides: a wide top over a
    // plane seen beside one side is as often a member's top over another
    // part's edge (a tube's top over a beam seen past its end) as a
    // block whose far side hides the plate.
    find_tee_by(l, s, points, |top, height| {
        let falls = || face_falls_from(top, height, &l.normal, s.neighbour_radius_mm, s.coplanar_tolerance_mm, points);
        (!narrow(top) && height > s.lap_step_max_mm && falls()).then_some(true)
    })
    .filter(TeeLayers::two_sided)
}

/// [`find_tee`] with the tops `web_top` takes (given the top and its
/// height over the layer under it), and says whether each was found by
/// its falling faces (`Some(true)`) or its shape (`Some(false)`).
fn find_tee_by(
    l: &Layers,
    s: &Selection,
    points: &[Point],
    web_top: impl Fn(&PlaneCluster, f64) -> Option<bool>,
) -> Option<TeeLayers> {
    let mut one_sided = None;
    for (upper, layer) in l.layers.iter().enumerate() {
        let top = &layer[0];
        if upper + 1 >= l.layers.len() {
            continue;
        }
        // A web's top is its workpiece's nearest surface: a narrow plane
        // under a larger one lies below the workpiece's top (a V-groove's
        // root land between its plates), not on top of a web.
        if l.layers[..upper].iter().any(|nearer| nearer[0].area_mm2 > top.area_mm2) {
            continue;
        }
        let flange = upper + 1;
        let height = l.depth(flange) - l.offset(top);
        if !stands_as_web(height, top.width_mm(), s) {
            continue;
        }
        let Some(by_faces) = web_top(top, height) else {
            continue;
        };
        // On each side the piece the web's top stands beside, else the
        // largest: a plate of another workpiece grouped with the tee can
        // lie in the flange's layer, larger than the flange's piece
        // (multi-05 of the several-workpiece suite's draw 2, whose I-butt
        // plate 2.5 mm over the flange was taken for it).
        let on_side = |positive: bool| {
            let side: Vec<usize> = (0..l.layers[flange].len())
                .filter(|&k| {
                    let side = side_of(top, &l.layers[flange][k], &l.normal);
                    if positive { side > 0.0 } else { side < 0.0 }
                })
                .collect();
            let pieces: Vec<&PlaneCluster> = side.iter().map(|&k| &l.layers[flange][k]).collect();
            side.get(standing_beside(top, &pieces, &l.normal, points, MAX_JOINT_OPENING_MM)).copied()
        };
        // A member's top found by its faces is wide, and one plate round
        // it is one piece whose centroid lies on neither side: each side's
        // piece is the one most seen beside the top there.
        let beside_faces = |positive: bool| {
            let side = usize::from(positive);
            let seen: Vec<f64> =
                l.layers[flange].iter().map(|c| seen_beside(top, c, &l.normal, points)[side]).collect();
            let most = (0..seen.len()).max_by(|&a, &b| seen[a].total_cmp(&seen[b]))?;
            (seen[most] >= FALL_MIN_POINTS as f64 * spacing_of(top).powi(2)).then_some(most)
        };
        let sides = if by_faces { [beside_faces(false), beside_faces(true)] } else { [on_side(false), on_side(true)] };
        let found = TeeLayers { top: (upper, 0), flange, sides, by_faces };
        if found.two_sided() {
            return Some(found);
        }
        if one_sided.is_none() && found.sides.iter().any(Option::is_some) {
            one_sided = Some(found);
        }
    }
    one_sided
}

/// How many times its top's width a strip no higher than a lap's upper
/// plate is thick must stand over the plane beside it to be a web
/// standing on its flange, under a tee's request. A web is a plate
/// standing on its edge: the tee suite's webs are 40 to 100 mm tall and
/// 4 to 12 mm thick, the process suite's short webs 15 to 25 mm tall (3.3
/// to 3.7 times their thickness, their tops measured about 1 mm narrower
/// still). A bar or a clamp lying flat on a plate is about as wide as it
/// is tall or wider (the fault suite's example clamp: 25 mm tall, 30 mm
/// wide), and a lap's upper plate, as tall as it is thick, is far wider.
pub const WEB_MIN_HEIGHT_PER_WIDTH: f64 = 1.5;

/// Whether a long narrow top `width_mm` wide, `height_mm` over the plane
/// beside it, stands there as a web's top: no higher than a web stands
/// (`web_height_max_mm`), and either higher than any lap's upper plate is
/// thick (`lap_step_max_mm`) or, a short web under a tee's request, at
/// least [`WEB_MIN_HEIGHT_PER_WIDTH`] times as tall as it is wide.
///
/// Without the request the height alone decides: a bar or clamp standing
/// on edge across a butt or lap joint (the fault suite's clamps: 15 to
/// 40 mm wide, 10 to 40 mm tall) lies over the plates on both of its
/// sides as a short web does over its flange, and only the user's naming
/// of the joint tells the two apart.
fn stands_as_web(height_mm: f64, width_mm: f64, s: &Selection) -> bool {
    let short_web_named = s.joint == Some(JointType::TFillet) && height_mm >= WEB_MIN_HEIGHT_PER_WIDTH * width_mm;
    height_mm <= s.web_height_max_mm && (height_mm > s.lap_step_max_mm || short_web_named)
}

/// The nearest layer of workpiece planes, its clusters largest first
/// (None when no plane faces the camera): where no web's top is found,
/// the flange of a tee whose top is out of view (a crop round its root),
/// for [`super::super::web_face`] to find the web's face standing on.
pub fn nearest_layer(planes: &[PlaneCluster], s: &Selection) -> Option<Vec<PlaneCluster>> {
    let offset = |c: &PlaneCluster| s.normal.dot(&c.centroid);
    let mut facing: Vec<&PlaneCluster> = planes.iter().filter(|c| s.faces_camera(c)).collect();
    facing.sort_by(|a, b| offset(a).total_cmp(&offset(b)));
    // Chained as `robust_select` chains its layers: from the nearest one.
    let first = offset(facing.first()?);
    let mut layer: Vec<&PlaneCluster> =
        facing.into_iter().take_while(|c| offset(c) - first <= s.coplanar_tolerance_mm).collect();
    layer.sort_by(|a, b| b.area_mm2.total_cmp(&a.area_mm2));
    Some(layer.into_iter().cloned().collect())
}

/// Where a lap's plates are: the upper and the lower layer.
fn find_lap(l: &Layers, s: &Selection, points: &[Point]) -> Result<(usize, usize), BackgroundError> {
    for upper in 0..l.layers.len() {
        for lower in upper + 1..l.layers.len() {
            let step = l.depth(lower) - l.depth(upper);
            if step > s.lap_step_max_mm {
                break;
            }
            if step >= s.lap_step_min_mm {
                // Two plates side by side on top are a butt joint's.
                if let [first, second, ..] = l.layers[upper].as_slice()
                    && second.area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * first.area_mm2
                {
                    return Err(BackgroundError::LooksLikeButt {
                        first_mm2: first.area_mm2,
                        second_mm2: second.area_mm2,
                        tolerance_mm: s.coplanar_tolerance_mm,
                    });
                }
                // The lower plate seen on both sides of the upper one: the
                // upper one lies across it. Split into two clusters by it,
                // or one cluster round its end (a clamp shorter than the
                // plate is wide).
                let (top, under) = (&l.layers[upper][0], &l.layers[lower]);
                let across = |first_mm2: f64, second_mm2: f64| BackgroundError::LiesAcross {
                    top_mm2: top.area_mm2,
                    above_mm: step,
                    first_mm2,
                    second_mm2,
                };
                if let Some(piece) = under[1..].iter().find(|c| {
                    c.area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * under[0].area_mm2
                        && lies_across(top, &under[0], c, &l.normal)
                }) {
                    return Err(across(under[0].area_mm2, piece.area_mm2));
                }
                // The whole layer under it: a bar lying across a plate can
                // cut it into pieces each smaller than a quarter of the
                // plate beside them (fault-clamp-i-butt-02, whose clamp
                // over an I-butt joint was planned as a lap 62 mm off).
                if top.elongation >= BAR_ELONGATION {
                    let [one, other] = under
                        .iter()
                        .map(|c| seen_beside(top, c, &l.normal, points))
                        .fold([0.0, 0.0], |[a, b], [one, other]| [a + one, b + other]);
                    let (larger, smaller) = (one.max(other), one.min(other));
                    if smaller > 0.0 && smaller >= SIDE_BY_SIDE_AREA_RATIO * larger {
                        return Err(across(larger, smaller));
                    }
                }
                return Ok((upper, lower));
            }
        }
    }
    Err(BackgroundError::NoLapStep {
        found: l.found,
        offsets_mm: l.offsets_mm.clone(),
        min_mm: s.lap_step_min_mm,
        max_mm: s.lap_step_max_mm,
    })
}

/// A lap's lower plate is the plane its upper plate's edge stands on,
/// which is not always the largest of the layer under it: a part touching
/// the lower plate a millimetre or two lower lies in the same layer (within
/// the coplanar tolerance), and can be the larger of the two
/// (fault-touching-part-lap-00 of fault draw 7: the part, 33 mm beyond the
/// strip of lower plate beside the upper plate's edge and 1.79 mm lower,
/// was taken for the lower plate, and the root was planned 1.79 mm under
/// the lower plate's top). The index into `l.layers[lower]` of the plate
/// [`standing_beside`] the upper plate.
///
/// Between a lap's upper plate and its lower plate only the band the step
/// hides from the camera lies unseen (the step times the tangent of the
/// view's slant, taken at most 45 degrees here), with the rim the plane
/// criterion trims off each plate (a neighbour radius). A plate of the
/// layer further across than that is no lower plate the upper one stands
/// on, however near: at 1 mm voxels multi-03's I-butt, its plates seen as
/// one plane, stands 16 mm from a V-butt plate 3.8 mm lower, of another
/// workpiece the table between them did not set apart.
fn lower_plate_of(l: &Layers, upper: usize, lower: usize, s: &Selection, points: &[Point]) -> usize {
    let top = &l.layers[upper][0];
    let under: Vec<&PlaneCluster> = l.layers[lower].iter().collect();
    let step = l.depth(lower) - l.offset(top);
    let hidden_mm = step.max(0.0) + 2.0 * s.neighbour_radius_mm;
    standing_beside(top, &under, &l.normal, points, hidden_mm.min(MAX_JOINT_OPENING_MM))
}

/// The robust rule: plates are the nearest parallel layers that fit the
/// joint type; with no type given, the layers decide: two plates side by
/// side in the nearest such layer make a butt joint, two layers a plate
/// thickness apart with one plate on top a lap, and where both fit, the
/// one whose top plate is nearer the camera (the workpiece's top) unless
/// that top is too small beside the butt plates to be a plate (a clamp).
/// `points` is the frame the clusters index.
pub fn robust_select(planes: Vec<PlaneCluster>, s: &Selection, points: &[Point]) -> Result<Selected, BackgroundError> {
    let mut planes: Vec<PlaneCluster> = planes.into_iter().filter(|c| s.faces_camera(c)).collect();
    let found = planes.len();
    if found < 2 {
        return Err(BackgroundError::TooFewPlanes { found });
    }
    let offset = |c: &PlaneCluster| s.normal.dot(&c.centroid);
    planes.sort_by(|a, b| offset(a).total_cmp(&offset(b)));
    let offsets_mm: Vec<f64> = planes.iter().map(|c| (offset(c) * 10.0).round() / 10.0).collect();

    // Layers: runs of clusters whose offsets agree, nearest the camera first.
    let mut layers: Vec<Vec<PlaneCluster>> = Vec::new();
    for c in planes {
        match layers.last_mut() {
            Some(layer) if offset(&c) - offset(&layer[0]) <= s.coplanar_tolerance_mm => layer.push(c),
            _ => layers.push(vec![c]),
        }
    }
    for layer in &mut layers {
        layer.sort_by(|a, b| b.area_mm2.total_cmp(&a.area_mm2));
    }
    let (cut_off, cuts_read) = set_apart_cut_pieces(&mut layers, points);
    let l = Layers { layers, normal: s.normal, found, offsets_mm };

    let butt = |l: &Layers, pos: usize, why: String| {
        let [a, b] = [&l.layers[pos][0], &l.layers[pos][1]];
        let evidence = format!(
            "two plates side by side ({:.0} and {:.0} mm², {:.1} mm apart along the normal){why}",
            a.area_mm2,
            b.area_mm2,
            (l.offset(b) - l.offset(a)).abs()
        );
        (Layout::Butt, [(pos, 0), (pos, 1)], l.depth_behind(pos), evidence)
    };
    let lap = |l: &Layers, (upper, lower): (usize, usize), why: String| {
        let k = lower_plate_of(l, upper, lower, s, points);
        let (top, under) = (&l.layers[upper][0], &l.layers[lower][k]);
        let evidence = format!(
            "an upper plate of {:.0} mm² {:.1} mm over a lower one of {:.0} mm²{why}",
            top.area_mm2,
            l.offset(under) - l.offset(top),
            under.area_mm2
        );
        (Layout::Lap, [(upper, 0), (lower, k)], l.depth_behind(lower), evidence)
    };
    let tee_found = find_tee(&l, s, points);
    let tee = |l: &Layers, t: &TeeLayers| {
        let top = t.top(l);
        let sides = match t.sides {
            [Some(_), Some(_)] => {
                format!("seen on both of its sides ({:.0} and {:.0} mm²)", t.piece_mm2(l, 0), t.piece_mm2(l, 1))
            }
            _ => format!("seen on one of its sides only ({:.0} mm²)", t.piece_mm2(l, 0).max(t.piece_mm2(l, 1))),
        };
        let evidence = format!(
            "a web's top of {:.0} mm², about {:.0} mm wide, {:.1} mm over a flange {sides}",
            top.area_mm2,
            top.width_mm(),
            t.height(l)
        );
        // The larger flange piece is the second plate; the other stays a
        // layer mate.
        let larger = if t.piece_mm2(l, 0) >= t.piece_mm2(l, 1) { t.sides[0] } else { t.sides[1] };
        (Layout::Tee, [t.top, (t.flange, larger.unwrap_or(0))], l.depth_behind(t.flange), evidence)
    };
    let (layout, picks, depth_to_support_mm, evidence) = match (s.joint, tee_found) {
        (Some(JointType::TFillet), Some(t)) => tee(&l, &t),
        (Some(JointType::TFillet), None) => {
            return Err(BackgroundError::NoWeb {
                found: l.found,
                offsets_mm: l.offsets_mm.clone(),
                min_mm: s.lap_step_max_mm,
                min_height_per_width: WEB_MIN_HEIGHT_PER_WIDTH,
                max_mm: s.web_height_max_mm,
                max_width_mm: s.web_thickness_max_mm,
            });
        }
        (Some(joint), Some(t)) if t.two_sided() && !t.by_faces => {
            let top = t.top(&l);
            return Err(BackgroundError::LooksLikeTee {
                joint,
                top_mm2: top.area_mm2,
                width_mm: top.width_mm(),
                height_mm: t.height(&l),
                first_mm2: t.piece_mm2(&l, 0),
                second_mm2: t.piece_mm2(&l, 1),
            });
        }
        // A top found by its falling faces is weighed last: a clamp or a
        // bar lying across a butt or lap joint stands over the plates too,
        // and the butt's or lap's own layers are the better evidence.
        (None, Some(t)) if t.two_sided() && !t.by_faces => tee(&l, &t),
        (Some(joint), _) if Layout::of(joint) == Layout::Butt => butt(&l, find_butt(&l, s, joint)?, String::new()),
        (Some(_), _) => lap(&l, find_lap(&l, s, points)?, String::new()),
        (None, _) => match (find_butt(&l, s, JointType::IButt), find_lap(&l, s, points)) {
            // A plate over the pair, not a clamp: as large as a plate beside
            // it, and over a lower plate of its own, not lying across the
            // pair (a clamp or a fixture over a butt joint's gap).
            (Ok(pos), Ok(lap_layers))
                if lap_layers.0 < pos
                    && lap_layers.1 != pos
                    && l.layers[lap_layers.0][0].area_mm2 >= SIDE_BY_SIDE_AREA_RATIO * l.layers[pos][1].area_mm2 =>
            {
                tracing::debug!(
                    rule = crate::rules::background::LAP_NEARER_THAN_BUTT_PAIR.id,
                    "a lap nearer than a butt pair"
                );
                lap(&l, lap_layers, " nearer the camera than the nearest coplanar pair".into())
            }
            // The lap's upper layer is the pair's, and the lap found no
            // second plate beside the first there: a plate and a piece.
            (Ok(pos), Ok((upper, lower))) if upper == pos => {
                return Err(BackgroundError::Ambiguous {
                    first_mm2: l.layers[pos][0].area_mm2,
                    second_mm2: l.layers[pos][1].area_mm2,
                    step_mm: l.depth(lower) - l.depth(upper),
                });
            }
            (Ok(pos), _) => butt(&l, pos, String::new()),
            (Err(BackgroundError::LooksLikeLap { .. }), Ok(lap_layers)) => {
                lap(&l, lap_layers, ", and no two plates side by side in one plane".into())
            }
            (Err(butt_error), Ok(lap_layers)) => lap(&l, lap_layers, format!("; not a butt joint: {butt_error}")),
            (Err(butt), Err(lap)) => match tee_found {
                // A top found by its falling faces (one found by its shape
                // and seen on both sides was taken above): a member
                // standing on a plate, where neither a butt nor a lap fits.
                Some(t) if t.two_sided() => tee(&l, &t),
                // Found by its shape, seen on one side only: a web whose
                // far side hides the flange, or a bar at a plate's edge. (A
                // top found by its faces seen so says nothing more than the
                // layers do.)
                Some(t) if !t.by_faces => {
                    let top = t.top(&l);
                    return Err(BackgroundError::OneSidedWeb {
                        top_mm2: top.area_mm2,
                        width_mm: top.width_mm(),
                        height_mm: t.height(&l),
                        beside_mm2: t.piece_mm2(&l, 0).max(t.piece_mm2(&l, 1)),
                    });
                }
                _ => return Err(BackgroundError::Unrecognised { butt: Box::new(butt), lap: Box::new(lap) }),
            },
        },
    };
    let [(pair_layer, first_k), (second_layer, second_k)] = picks;
    let support_between_plates = layout == Layout::Butt
        && l.layers.get(pair_layer + 1).is_some_and(|behind| {
            let (a, b) = (&l.layers[pair_layer][first_k], &l.layers[second_layer][second_k]);
            behind.iter().all(|c| lies_between_pair(a, b, c, &l.normal))
        });
    // Take the two plates out of their layers, the later pick first so the
    // earlier one's place does not move.
    let mut layers = l.layers;
    let mut take = |(layer, k): (usize, usize)| layers[layer].swap_remove(k);
    let (second, first) = (take(picks[1]), take(picks[0]));
    let mut layer_mates = [layers[picks[0].0].clone(), std::mem::take(&mut layers[picks[1].0])];
    for (mates, (layer, _)) in layer_mates.iter_mut().zip(picks) {
        mates.extend(cut_off[layer].iter().cloned());
    }
    let workpiece = Workpiece { plates: [first, second], depth_to_support_mm, support_between_plates, layer_mates };
    let web_by_faces = layout == Layout::Tee && tee_found.is_some_and(|t| t.by_faces);
    Ok(Selected { workpiece, layout, evidence: evidence + &cuts_read, web_by_faces })
}

/// Takes out of each layer the pieces a break in the image cut off a
/// larger cluster of it ([`image_break`]): no plates of their own, but
/// pieces of that plate, kept as its layer mates. Returns them per layer,
/// and in words what was read.
fn set_apart_cut_pieces(layers: &mut [Vec<PlaneCluster>], points: &[Point]) -> (Vec<Vec<PlaneCluster>>, String) {
    let mut cut_off = vec![Vec::new(); layers.len()];
    let mut read = String::new();
    for k in 0..layers.len() {
        let (front, back) = layers.split_at_mut(k + 1);
        let behind: Vec<&PlaneCluster> = back.iter().flatten().collect();
        let layer = &mut front[k];
        let cuts = image_break::cut_pieces(layer, &behind, points);
        for cut in &cuts {
            let (piece, of) = (&layer[cut.piece], &layer[cut.of]);
            tracing::debug!(
                piece_mm2 = piece.area_mm2,
                of_mm2 = of.area_mm2,
                width_mm = cut.found.width_mm,
                run_on_mm = cut.found.run_on_mm,
                "a piece cut off a plate by a break in the image"
            );
            read += &format!(
                "; {:.0} mm² beside the {:.0} mm² plane is a piece of it: the {:.1} mm break between them runs on \
                 {:.0} mm across the surface behind, a break in the image",
                piece.area_mm2, of.area_mm2, cut.found.width_mm, cut.found.run_on_mm
            );
        }
        // Largest place first, so the places still to take do not move.
        for cut in cuts.iter().rev() {
            cut_off[k].push(layer.remove(cut.piece));
        }
    }
    (cut_off, read)
}
