//! CPU tests of `shading`: the light loop passes every effect bit of the frame through to
//! `lighting::shade` (the inverse-square cut included) and fixes only the specular bit to the
//! compiled variant; the cursors walk exactly their lists; the surface fetch and the variant
//! effects are what the techniques rely on.
use super::*;
use crate::lighting::{attenuation, inverse_square_cut, light_touches, shade};
use crate::test_support::{frame_params, gbuffer, grid, test_lights, Rng};

/// Geometry pixels of a synthetic G-buffer, with a diffuse and a specular material.
fn surfaces(rng: &mut Rng) -> (Vec<Surface>, Vec<PointLight>) {
    let g = grid(40, 24, 16);
    let gb = gbuffer(&g, rng);
    let lights = test_lights(&g, rng, 300, 0);
    let materials = [MaterialGpu { specular: 0.0, roughness: 1.0, opacity: 1.0, _pad: 0.0 }, MaterialGpu { specular: 0.7, roughness: 0.3, opacity: 1.0, _pad: 0.0 }];
    let p = frame_params(g, lights.len() as u32);
    let s = (0..g.width * g.height)
        .filter(|&i| !reconstruct::is_background(gb.depth[i as usize]))
        .map(|i| fetch_surface(&p, i, gb.depth[i as usize], &gb.normals, gb.albedo[i as usize], &materials))
        .collect();
    (s, lights)
}

/// The sum `lighting::shade` gives with `effects`, lights in index order.
fn direct(s: &Surface, lights: &[PointLight], effects: u32) -> Vec3 {
    lights.iter().fold(Vec3::ZERO, |sum, l| sum + shade(s.pos, s.normal, s.albedo, s.specular, s.roughness, l, effects))
}

/// The loop over all lights (the deferred list), in a variant.
fn looped<const SPECULAR: bool>(s: &Surface, lights: &[PointLight], frame_effects: u32) -> Vec3 {
    let mut sum = Vec3::ZERO;
    let n = shade_lights::<SPECULAR, true, _>(s, frame_effects, lights.len() as u32, lights, &light_range(0, lights.len() as u32), &mut sum);
    assert_eq!(n, lights.len() as u32);
    sum
}

/// With `EFFECT_INVERSE_SQUARE_CUT` the loop equals `lighting::shade` with that bit, bit for bit,
/// in both variants and with the other bits of a frame (culling modes, textures) around it; and
/// it differs from the Karis-window sum wherever the two falloffs give different light.
#[test]
fn the_loop_shades_with_the_frames_falloff() {
    let mut rng = Rng(41);
    let (surfaces, lights) = surfaces(&mut rng);
    let mut differing = 0;
    for s in &surfaces {
        for other in [0, EFFECT_TEXTURES | EFFECT_CULL_PLANES, EFFECT_CULL_EXACT] {
            let cut = EFFECT_INVERSE_SQUARE_CUT | other;
            assert_eq!(looped::<false>(s, &lights, cut), direct(s, &lights, EFFECT_INVERSE_SQUARE_CUT), "{s:?} frame effects {cut:#x}");
            assert_eq!(looped::<true>(s, &lights, cut), direct(s, &lights, EFFECT_INVERSE_SQUARE_CUT | EFFECT_SPECULAR), "{s:?} frame effects {cut:#x}");
            assert_eq!(looped::<false>(s, &lights, other), direct(s, &lights, 0), "{s:?} frame effects {other:#x}");
        }
        // Where some light reaches the pixel (n·l > 0) with a falloff the cut changes, the sums differ.
        let falloffs_differ = lights.iter().any(|l| {
            let c = Vec3::from_array(l.position);
            let d2 = lighting::distance2(s.pos, c);
            light_touches(l, s.pos) && s.normal.dot(c - s.pos) > 0.0 && l.intensity > 0.0 && attenuation(d2, l.radius) != inverse_square_cut(d2, l.radius)
        });
        if falloffs_differ {
            assert_ne!(looped::<true>(s, &lights, EFFECT_INVERSE_SQUARE_CUT), looped::<true>(s, &lights, 0), "{s:?}: the cut must change the light");
            differing += 1;
        }
    }
    assert!(differing * 4 > surfaces.len(), "a quarter of the pixels must see a light whose falloffs differ: {differing} of {}", surfaces.len());
}

/// The specular bit is the variant's: `_diffuse` never adds the lobe (even if the frame says
/// specular), `_specular` always does; on specular materials the two differ.
#[test]
fn the_specular_bit_is_the_variants() {
    let mut rng = Rng(43);
    let (surfaces, lights) = surfaces(&mut rng);
    let mut lobes = 0;
    for s in &surfaces {
        for fx in [0, EFFECT_SPECULAR, EFFECT_SPECULAR | EFFECT_INVERSE_SQUARE_CUT] {
            let rest = fx & !EFFECT_SPECULAR;
            assert_eq!(looped::<false>(s, &lights, fx), direct(s, &lights, rest));
            assert_eq!(looped::<true>(s, &lights, fx), direct(s, &lights, rest | EFFECT_SPECULAR));
        }
        if s.specular > 0.0 && looped::<true>(s, &lights, 0) != looped::<false>(s, &lights, 0) {
            lobes += 1;
        }
    }
    assert!(lobes > 0, "some specular pixel must show a highlight");
    assert_eq!(variant_effects::<false>(EFFECT_SPECULAR | EFFECT_INVERSE_SQUARE_CUT), EFFECT_INVERSE_SQUARE_CUT);
    assert_eq!(variant_effects::<true>(EFFECT_INVERSE_SQUARE_CUT), EFFECT_INVERSE_SQUARE_CUT | EFFECT_SPECULAR);
    assert_eq!(variant_effects::<true>(u32::MAX), u32::MAX);
}

/// The lights of `list` in order, stepping until `NO_LIGHT`; the end stays the end.
fn walk<L: LightList>(list: &L) -> Vec<u32> {
    let (mut pos, mut out) = (list.start(), Vec::new());
    loop {
        let (l, next) = list.step(pos);
        if l == NO_LIGHT {
            assert_eq!(list.step(pos).0, NO_LIGHT, "the end stays the end");
            return out;
        }
        out.push(l);
        pos = next;
    }
}

/// Every list walks its entries once, in order, then stays at `NO_LIGHT`; the loop visits exactly
/// the listed lights at every length around its 16-light iterations (and one light per
/// iteration), and a forward+ linked list gives the sum of the same lights in list order.
#[test]
fn cursors_walk_exactly_their_lists() {
    let mut rng = Rng(47);
    let (surfaces, lights) = surfaces(&mut rng);
    let s = &surfaces[surfaces.len() / 2];
    for len in [0u32, 1, 7, 8, 15, 16, 17, 31, 32, 33, 100] {
        let list: Vec<u32> = (0..len).map(|_| rng.below(lights.len() as u32)).collect();
        let first = rng.below(5);
        let mut buffer = vec![NO_LIGHT; first as usize];
        buffer.extend(&list);
        buffer.push(7); // past the range: never read
        let range = index_range(first, len, |t| buffer[t as usize]);
        assert_eq!(walk(&range), list, "range of {len}");
        assert_eq!(walk(&light_range(first, len)), (first..first + len).collect::<Vec<_>>(), "lights {first}..+{len}");
        // Linked: nodes in scrambled slots, pushed on the head like the culling does (last first).
        let mut slots: Vec<u32> = (0..len + 3).collect();
        for k in (1..slots.len()).rev() {
            slots.swap(k, rng.below(k as u32 + 1) as usize);
        }
        let mut nodes = vec![0u32; 2 * slots.len()];
        let mut head = NO_NODE;
        for (k, &l) in list.iter().enumerate().rev() {
            let node = slots[k];
            nodes[2 * node as usize] = l;
            nodes[2 * node as usize + 1] = head;
            head = node;
        }
        assert_eq!(walk(&linked_lights(head, &nodes)), list, "linked list of {len}");
        let chosen: Vec<PointLight> = list.iter().map(|&l| lights[l as usize]).collect();
        let want = direct(s, &chosen, EFFECT_INVERSE_SQUARE_CUT | EFFECT_SPECULAR);
        // The Forward+ fragment shader walks it one light per iteration; unrolled the same.
        let mut sum = Vec3::ZERO;
        assert_eq!(shade_lights::<true, false, _>(s, EFFECT_INVERSE_SQUARE_CUT, lights.len() as u32, &lights, &linked_lights(head, &nodes), &mut sum), len, "linked list of {len}");
        assert_eq!(sum, want, "linked list of {len}");
        let mut sum = Vec3::ZERO;
        assert_eq!(shade_lights::<true, true, _>(s, EFFECT_INVERSE_SQUARE_CUT, lights.len() as u32, &lights, &linked_lights(head, &nodes), &mut sum), len, "linked list of {len}");
        assert_eq!(sum, want, "linked list of {len}, unrolled");
        let mut sum = Vec3::ZERO;
        assert_eq!(shade_lights::<true, true, _>(s, EFFECT_INVERSE_SQUARE_CUT, lights.len() as u32, &lights, &index_range(first, len, |t| buffer[t as usize]), &mut sum), len);
        assert_eq!(sum, want, "range of {len}");
    }
}

/// A list buffer's range reads its entries where it lies inside the buffer and is empty
/// wherever it does not (a list the assignment could not place: nothing past the buffer is read,
/// which the unchecked GPU read relies on; `crate::unchecked`).
#[test]
fn list_ranges_are_empty_unless_inside_their_buffer() {
    let buffer = [5u32, 6, 7, 8];
    let r = list_range(&buffer, 1, 3);
    assert_eq!(walk(&r), vec![6, 7, 8]);
    assert_eq!(walk(&list_range(&buffer, 0, 4)), buffer.to_vec());
    assert_eq!(walk(&list_range(&buffer, 4, 0)), Vec::<u32>::new());
    for (first, count) in [(2, 3), (0, 5), (5, 0), (4, 1), (u32::MAX, 2), (1, u32::MAX), (u32::MAX, u32::MAX)] {
        let r = list_range(&buffer, first, count);
        assert_eq!(r.end(), Some(r.start()), "{first}+{count} lies outside a buffer of 4");
        assert_eq!(walk(&r), Vec::<u32>::new());
    }
}

/// A list shaded in two parts into one sum equals the list shaded at once (tiled rounds).
#[test]
fn a_list_in_parts_sums_like_one_list() {
    let mut rng = Rng(53);
    let (surfaces, lights) = surfaces(&mut rng);
    for s in surfaces.iter().step_by(7) {
        let split = rng.below(lights.len() as u32);
        let mut parts = Vec3::ZERO;
        shade_lights::<true, true, _>(s, EFFECT_SPECULAR, lights.len() as u32, &lights, &light_range(0, split), &mut parts);
        shade_lights::<true, true, _>(s, EFFECT_SPECULAR, lights.len() as u32, &lights, &light_range(split, lights.len() as u32 - split), &mut parts);
        assert_eq!(parts, looped::<true>(s, &lights, EFFECT_SPECULAR));
    }
}

/// The surface fetch decodes the G-buffer words and the material, at every normal precision.
#[test]
fn fetch_surface_decodes_the_gbuffer() {
    let g = grid(8, 4, 16);
    let materials = [MaterialGpu { specular: 0.0, roughness: 1.0, opacity: 1.0, _pad: 0.0 }, MaterialGpu { specular: 0.25, roughness: 0.5, opacity: 1.0, _pad: 0.0 }];
    let n = [0.36f32, 0.48, 0.8];
    for precision in [PRECISION_OCT8, PRECISION_OCT12, PRECISION_OCT16, PRECISION_F32] {
        let prec = octahedral::Precision::from_u32(precision);
        let w = octahedral::encode(n, prec);
        let words: Vec<u32> = (0..32).flat_map(|_| w.into_iter().chain([0]).take(prec.gbuffer_words() as usize)).collect();
        let mut p = frame_params(g, 0);
        p.normal_precision = precision;
        let z = g.near / 12.5;
        let s = fetch_surface(&p, 13, z, &words, 0x0133_6699, &materials);
        assert_eq!(s.pos, reconstruct::view_position(&g, 5, 1, reconstruct::distance_from_depth(g.near, z)));
        assert_eq!(s.normal, Vec3::from_array(octahedral::decode(w, prec)), "precision {precision}");
        assert_eq!(s.albedo, Vec3::new(0x99 as f32, 0x66 as f32, 0x33 as f32) * (1.0 / 255.0));
        assert_eq!((s.specular, s.roughness), (0.25, 0.5));
    }
}

/// With `EFFECT_SPOT` each light's radiance is multiplied by its cone falloff (a point light's
/// marker record by exactly 1), and `shade_directional_lights` adds each directional light once:
/// the loop equals the direct sum of the model (`spot::spot_factor`, `lighting::shade_directional`).
#[test]
fn spots_and_directional_lights_follow_the_model() {
    use crate::light_types::*;
    use crate::spot::{spot_factor, Cone};
    let (all, lights) = surfaces(&mut Rng(23));
    let n = lights.len() as u32;
    let mut cut = false;
    for s in all.iter().step_by(7).take(60) {
        let cones: Vec<Cone> = (0..lights.len())
            .map(|i| {
                let to_surface = (s.pos - Vec3::from_array(lights[i].position)).normalize_or_zero();
                let axis = (to_surface + Vec3::new(0.3 * (i % 3) as f32, -0.2, 0.1)).normalize();
                Cone::new(axis, 0.1 + 0.05 * (i % 4) as f32, 0.4 + 0.1 * (i % 5) as f32)
            })
            .collect();
        let mut buffer = lights.clone();
        buffer.extend(cones.iter().enumerate().map(|(i, c)| if i % 4 == 3 { point_record() } else { spot_record(c) }));
        let dirs = [(Vec3::new(0.3, 0.9, 0.2).normalize(), [1.0, 0.9, 0.8], 0.7), (Vec3::new(-0.5, 0.2, 0.8).normalize(), [0.2, 0.4, 1.0], 1.5)];
        buffer.extend(dirs.iter().map(|&(d, c, i)| directional_record(d, c, i)));
        let effects = EFFECT_SPECULAR | light_effects(true, dirs.len() as u32);
        let mut expected = Vec3::ZERO;
        for (i, l) in lights.iter().enumerate() {
            let f = if i % 4 == 3 { 1.0 } else { spot_factor(Vec3::from_array(l.position), &cones[i], s.pos) };
            expected += shade(s.pos, s.normal, s.albedo, s.specular, s.roughness, l, effects) * f;
        }
        let mut sum = Vec3::ZERO;
        shade_lights::<true, true, _>(s, effects, n, &buffer, &light_range(0, n), &mut sum);
        assert_eq!(sum, expected, "cone falloff in the loop");
        let mut linked = Vec3::ZERO;
        let nodes: Vec<u32> = (0..n).flat_map(|l| [l, if l + 1 < n { l + 1 } else { NO_NODE }]).collect();
        shade_lights::<true, false, _>(s, effects, n, &buffer, &linked_lights(0, &nodes), &mut linked);
        assert_eq!(linked, expected, "cone falloff, one light per iteration");
        // Zeros (a lane whose loads are masked off): node 0 follows itself and the walk ends.
        let zeros = vec![0u32; nodes.len()];
        assert_eq!(shade_lights::<true, false, _>(s, effects, n, &buffer, &linked_lights(0, &zeros), &mut Vec3::default()), 1, "a self-linked node ends the list");
        cut |= expected.cmplt(direct(s, &lights, effects)).any();
        for &(d, c, i) in &dirs {
            expected += crate::lighting::shade_directional::<true>(s.pos, s.normal, s.albedo, s.specular, s.roughness, d, Vec3::from_array(c), i, effects);
        }
        shade_directional_lights::<true>(s, effects, n, &buffer, &mut sum);
        assert_eq!(sum, expected, "directional lights after the list");
        let mut none = Vec3::ZERO;
        shade_directional_lights::<true>(s, EFFECT_SPECULAR, n, &buffer, &mut none);
        assert_eq!(none, Vec3::ZERO, "no directional loop without the bit");
    }
    assert!(cut, "the cones cut some light");
}

/// `block_pixel` covers every pixel of a frame exactly once, at sizes that are and are not
/// multiples of the block and of the footprint, and each run of 32 invocations takes an 8 × 4
/// footprint.
#[test]
fn block_pixels_cover_the_frame_once_in_footprints() {
    for (w, h) in [(32u32, 8u32), (64, 16), (33, 9), (7, 3), (100, 37), (1, 1)] {
        let mut seen = vec![0u32; (w * h) as usize];
        let (gx, gy) = (w.div_ceil(BLOCK_WIDTH), h.div_ceil(BLOCK_HEIGHT));
        for y in 0..gy {
            for x in 0..gx {
                for local in 0..LINEAR_WORKGROUP {
                    let i = block_pixel(UVec3::new(x, y, 0), local, w, h);
                    if i != NO_PIXEL {
                        seen[i as usize] += 1;
                    }
                }
            }
        }
        assert!(seen.iter().all(|&n| n == 1), "{w}×{h}: every pixel once");
    }
    let (w, h) = (64, 16);
    for run in 0..LINEAR_WORKGROUP / 32 {
        let px: Vec<(u32, u32)> = (0..32).map(|k| block_pixel(UVec3::new(1, 1, 0), run * 32 + k, w, h)).map(|i| (i % w, i / w)).collect();
        let (x0, y0) = (px.iter().map(|p| p.0).min().unwrap(), px.iter().map(|p| p.1).min().unwrap());
        let (x1, y1) = (px.iter().map(|p| p.0).max().unwrap(), px.iter().map(|p| p.1).max().unwrap());
        assert_eq!((x1 - x0 + 1, y1 - y0 + 1), (FOOTPRINT_WIDTH, FOOTPRINT_HEIGHT), "run {run}");
    }
}
