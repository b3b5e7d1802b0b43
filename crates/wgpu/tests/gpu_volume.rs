//! Stencil shadow volumes against `shadowmap_eval`'s ray caster, at the report's
//! 480x270: the volumes' mask equals the ray-traced visibility except on silhouette
//! pixels (at most 0.1% of pixels differ), with the camera outside every volume
//! (z-pass and z-fail) and inside one (z-fail), on the city block and the indoor
//! room; and the GPU misclassification of every shadow-map technique against the
//! volumes matches the CPU misclassification against the ray caster on the same
//! frame. RTW over the spot fit and over the IPSM paraboloid: the GPU mask equals
//! eval's CPU mask. Projective shadows on the GPU equal their CPU reference on the
//! fence and the city block.

use glam::Vec3;
use shadowmap::Fitted;
use shadowmap_eval::bvh::Bvh;
use shadowmap_eval::config::{ConfigOptions, Configuration, standard_configurations};
use shadowmap_eval::mask::{GBuffer, ShadowMask as CpuMask};
use shadowmap_eval::metrics::ScreenGeometry;
use shadowmap_eval::raster::RasterOptions;
use shadowmap_eval::scene::Scene;
use shadowmap_eval::technique::{
    FrameContext, Technique, TechniqueKind, TechniqueOptions, eye_samples,
};
use shadowmap_frustum::{Aabb, Camera, Light, Projection};
use shadowmap_volume::{OccluderMask, Partition, ProjectiveShadow};
use shadowmap_wgpu::GpuContext;
use shadowmap_wgpu::depth::DepthBias;
use shadowmap_wgpu::render::{
    HeadlessRenderer, MaskValue, RenderOptions, ShadowBias, ShadowFilter, ShadowMask,
};
use shadowmap_wgpu::volume::{
    GpuSilhouette, ProjectiveRenderer, VolumeMethod, VolumeRenderer, VolumeScene, misclassification,
};

const W: u32 = 480;
const H: u32 = 270;

fn configuration(name: &str) -> Configuration {
    standard_configurations(&ConfigOptions::default().with_path_frames(1))
        .unwrap()
        .into_iter()
        .find(|c| c.name == name)
        .unwrap()
}

/// Is the eye in some caster's shadow (inside a volume)?
fn eye_in_shadow(bvh: &Bvh, eye: Vec3, light: &Light) -> bool {
    let p = eye.as_dvec3();
    let (dir, t_max) = match *light {
        Light::Directional { direction } => (-direction.as_dvec3().normalize(), f64::INFINITY),
        Light::Spot { position, .. } | Light::Point { position, .. } => {
            let to = position.as_dvec3() - p;
            (to.normalize(), to.length())
        }
    };
    bvh.occluded(p, dir, 0.0, t_max)
}

/// Pixels where the two masks differ (in classification or in coverage).
fn differing(gpu: &ShadowMask, cpu: &CpuMask) -> usize {
    gpu.values
        .iter()
        .zip(&cpu.lit)
        .filter(|(g, c)| g.lit() != **c)
        .count()
}

/// Renders the volume mask and compares it with the ray caster; returns the number
/// of differing pixels.
fn volume_vs_rays(
    ctx: &GpuContext,
    name: &str,
    scene: &Scene,
    camera: &Camera,
    light: &Light,
    method: VolumeMethod,
) -> usize {
    let bvh = Bvh::build(&scene.mesh).unwrap();
    let gbuffer = GBuffer::trace(&bvh, camera, W, H).unwrap();
    let truth = CpuMask::ray_traced(&gbuffer, &bvh, light).unwrap();
    let mut volumes = VolumeScene::new(&scene.mesh.triangles_f32()).unwrap();
    let gpu = VolumeRenderer::new()
        .render_mask(ctx, &mut volumes, camera, light, (W, H), method)
        .unwrap();
    let count = |v| gpu.values.iter().filter(|g| **g == v).count();
    let (lit, shadowed) = (count(MaskValue::Lit), count(MaskValue::Shadowed));
    let diff = differing(&gpu, &truth);
    eprintln!(
        "{name} {method:?}: {diff} of {} pixels differ ({:.3}%); lit {lit}, shadowed {shadowed}; \
         {} caster triangles, {} open",
        W * H,
        100.0 * diff as f64 / f64::from(W * H),
        volumes.casters().triangle_count(),
        volumes.open_triangles(),
    );
    assert!(
        lit > 1000 && shadowed > 1000,
        "{name}: a trivial mask (lit {lit}, shadowed {shadowed})"
    );
    diff
}

fn assert_close(name: &str, diff: usize) {
    assert!(
        diff as f64 <= 1e-3 * f64::from(W * H),
        "{name}: {diff} pixels differ"
    );
}

#[test]
fn volumes_match_the_ray_caster_with_the_camera_outside() {
    let Some(ctx) = shadowmap_wgpu::context::test_context(
        "volumes_match_the_ray_caster_with_the_camera_outside",
    ) else {
        return;
    };
    // Directional (city block, two lights), point (indoor room), spot (city block).
    for name in ["behind", "top_down", "point_inside", "facing_spot"] {
        let config = configuration(name);
        let bvh = Bvh::build(&config.scene.mesh).unwrap();
        assert!(!eye_in_shadow(&bvh, config.camera().eye(), &config.light));
        for method in [VolumeMethod::ZPass, VolumeMethod::ZFail] {
            let diff = volume_vs_rays(
                &ctx,
                name,
                &config.scene,
                config.camera(),
                &config.light,
                method,
            );
            assert_close(name, diff);
        }
    }
}

/// The first of `candidates` in some caster's shadow, looking along `forward`.
fn camera_in_shadow(
    bvh: &Bvh,
    light: &Light,
    candidates: impl IntoIterator<Item = Vec3>,
    forward: Vec3,
    (near, far): (f32, f32),
) -> Camera {
    let eye = candidates
        .into_iter()
        .find(|&eye| eye_in_shadow(bvh, eye, light))
        .expect("a candidate eye in shadow");
    Camera::look_to(
        eye,
        forward.normalize(),
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 16.0 / 9.0, near, far),
    )
    .unwrap()
}

/// Z-fail's mask equals the rays' with the eye inside a shadow volume, where z-pass
/// miscounts every pixel by the volume the eye is in.
fn inside_a_volume(ctx: &GpuContext, name: &str, config: &Configuration, camera: &Camera) {
    let (scene, light) = (&config.scene, &config.light);
    let z_fail = volume_vs_rays(ctx, name, scene, camera, light, VolumeMethod::ZFail);
    assert_close(name, z_fail);
    let z_pass = volume_vs_rays(ctx, name, scene, camera, light, VolumeMethod::ZPass);
    assert!(
        z_pass as f64 > 0.05 * f64::from(W * H),
        "{name}: z-pass: only {z_pass} pixels differ"
    );
}

#[test]
fn z_fail_is_right_with_the_camera_inside_a_volume() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("z_fail_is_right_with_the_camera_inside_a_volume")
    else {
        return;
    };
    // The city block: a street-level eye in a building's shadow (the sun low behind
    // it), found on the street grid.
    let config = configuration("behind");
    let bvh = Bvh::build(&config.scene.mesh).unwrap();
    let streets = (0..80)
        .flat_map(|i| (0..9).map(move |j| (i, j)))
        .map(|(i, j)| Vec3::new(-98.0 + 2.5 * i as f32, 1.7, -100.0 + 25.0 * j as f32 - 1.0));
    let forward = Vec3::new(1.0, -0.08, 0.25);
    let camera = camera_in_shadow(&bvh, &config.light, streets, forward, (0.5, 400.0));
    inside_a_volume(&ctx, "city block, camera in shadow", &config, &camera);
    // The indoor room: an eye under the table, in its shadow from the ceiling lamp,
    // looking out over the floor toward the column.
    let config = configuration("point_inside");
    let bvh = Bvh::build(&config.scene.mesh).unwrap();
    let under_table = (0..10)
        .flat_map(|i| (0..6).map(move |j| (i, j)))
        .map(|(i, j)| Vec3::new(-1.4 + 0.2 * i as f32, 0.5, -0.7 + 0.2 * j as f32));
    let forward = Vec3::new(1.0, -0.25, 0.7);
    let camera = camera_in_shadow(&bvh, &config.light, under_table, forward, (0.05, 30.0));
    inside_a_volume(&ctx, "indoor room, camera in shadow", &config, &camera);
}

#[test]
fn open_casters_are_reported() {
    let room = Scene::indoor_room();
    let scene = VolumeScene::new(&room.mesh.triangles_f32()).unwrap();
    assert!(scene.open_triangles() > 0);
    assert!(scene.first_open_edge().is_some());
    // The furniture (closed boxes and the column) casts.
    assert!(scene.casters().triangle_count() > 200);
    let bad = VolumeScene::new(&[[Vec3::ZERO, Vec3::X, Vec3::new(f32::NAN, 0.0, 0.0)]]);
    assert!(bad.is_err());
}

/// Lookup bias in depth units, and the rasterizer bias (constant, slope): the same
/// for the CPU reference rasterizer and the GPU depth pass.
const LOOKUP_BIAS: f64 = 1e-5;
const RASTER_CONSTANT: i32 = 64;
const RASTER_SLOPE: f32 = 1.5;

#[test]
fn gpu_misclassification_matches_the_cpu_for_every_technique() {
    let Some(ctx) = shadowmap_wgpu::context::test_context(
        "gpu_misclassification_matches_the_cpu_for_every_technique",
    ) else {
        return;
    };
    // A directional, a spot and a point light: every technique of each (RTW over
    // the uniform fit, the spot fit and the IPSM paraboloid included). Not
    // "overhead": with the light straight down every wall is edge-on to it, and
    // there the two references themselves (volumes and rays) disagree on 0.29% of
    // the pixels, which a technique's rate inherits.
    let mut checked = Vec::new();
    for name in ["behind", "facing_spot", "point_mid"] {
        checked.extend(misclassification_gaps(&ctx, &configuration(name)));
    }
    for kind in TechniqueKind::ALL {
        assert!(checked.contains(&kind), "{} not compared", kind.name());
    }
}

/// One configuration's frame at 480x270, traced on the CPU: what eval's
/// misclassification and the CPU reference masks are computed from.
struct ReportFrame<'c> {
    config: &'c Configuration,
    gbuffer: GBuffer,
    truth: CpuMask,
    samples: Vec<shadowmap_rtw::EyeSample>,
    pixels_per_radian: f32,
    triangles: Vec<[Vec3; 3]>,
}

impl<'c> ReportFrame<'c> {
    fn new(config: &'c Configuration) -> Self {
        let (camera, light) = (config.camera(), &config.light);
        let bvh = Bvh::build(&config.scene.mesh).unwrap();
        let gbuffer = GBuffer::trace(&bvh, camera, W, H).unwrap();
        let truth = CpuMask::ray_traced(&gbuffer, &bvh, light).unwrap();
        let samples = eye_samples(&gbuffer, camera);
        let screen = ScreenGeometry::new(camera, W, H).unwrap();
        Self {
            config,
            truth,
            samples,
            pixels_per_radian: screen.pixels_per_radian().unwrap() as f32,
            triangles: config.scene.mesh.triangles_f32(),
            gbuffer,
        }
    }

    /// The technique `kind` with a `budget` of texels: eval's CPU mask (its
    /// subdivision and reference rasterizer, looked up at the ray-traced surface of
    /// each pixel) and the backend's GPU mask, with the same biases.
    fn masks(
        &self,
        ctx: &GpuContext,
        renderer: &mut HeadlessRenderer,
        kind: TechniqueKind,
        budget: u64,
    ) -> (CpuMask, ShadowMask) {
        let config = self.config;
        let frame = FrameContext {
            camera: config.camera(),
            light: &config.light,
            scene: config.scene.scene_bounds().unwrap(),
            eye_samples: &self.samples,
            pixels_per_radian: self.pixels_per_radian,
        };
        let options = TechniqueOptions::default().with_texel_budget(budget);
        let technique = Technique::build(kind, &frame, &options)
            .unwrap_or_else(|e| panic!("{} on {}: {e}", kind.name(), config.name));
        if let Fitted::PointRtw { back, .. } = technique.shadow().fitted() {
            let sides = if back.is_some() {
                "two sides"
            } else {
                "one side"
            };
            eprintln!("{} on {}: {sides}", kind.name(), config.name);
        }
        let raster = RasterOptions::default()
            .with_depth_bias(f64::from(RASTER_CONSTANT), f64::from(RASTER_SLOPE));
        let map = technique.rasterize(&config.scene.mesh, &raster).unwrap();
        let cpu = CpuMask::from_map(&self.gbuffer, &technique, &map, LOOKUP_BIAS);
        let bias = DepthBias {
            constant: RASTER_CONSTANT,
            slope_scale: RASTER_SLOPE,
            clamp: 0.0,
        };
        let render = RenderOptions::default()
            .with_size(W, H)
            .with_filter(ShadowFilter::Hard)
            .with_bias(ShadowBias::new(bias, LOOKUP_BIAS as f32, 0.0));
        let gpu = renderer
            .render_shadow(
                ctx,
                &self.triangles,
                config.camera(),
                technique.shadow(),
                &render,
            )
            .unwrap_or_else(|e| panic!("{}: {e}", kind.name()))
            .mask;
        (cpu, gpu)
    }
}

/// Compares, for every technique of `config`'s light, the GPU misclassification
/// against the volumes with eval's CPU misclassification against the ray caster
/// (within 0.2 percentage points); returns the techniques compared.
fn misclassification_gaps(ctx: &GpuContext, config: &Configuration) -> Vec<TechniqueKind> {
    let (camera, light) = (config.camera(), &config.light);
    let frame = ReportFrame::new(config);
    let mut volumes = VolumeScene::new(&frame.triangles).unwrap();
    let volume_mask = VolumeRenderer::new()
        .render_mask(
            ctx,
            &mut volumes,
            camera,
            light,
            (W, H),
            VolumeMethod::ZFail,
        )
        .unwrap();
    let mut renderer = HeadlessRenderer::new();
    let mut checked = Vec::new();
    for kind in TechniqueKind::for_light(light) {
        let (cpu, gpu) = frame.masks(ctx, &mut renderer, kind, 512 * 512);
        let cpu = cpu.compare(&frame.truth);
        let (gpu, _) = misclassification(&gpu, &volume_mask);
        let gap = 100.0 * (gpu.rate() - cpu.rate());
        eprintln!(
            "{}: GPU misclassification {:.3}% ({} px), CPU {:.3}% ({} px), gap {gap:+.3} pp",
            kind.name(),
            100.0 * gpu.rate(),
            gpu.compared,
            100.0 * cpu.rate(),
            cpu.compared,
        );
        assert!(
            gap.abs() <= 0.2,
            "{} on {}: gap {gap} percentage points",
            kind.name(),
            config.name
        );
        checked.push(kind);
    }
    checked
}

/// RTW over the perspective base of the spot fit (`spot_rtw`), over the kept faces of
/// a cube map (`cube_rtw`, five and six faces) and over the sides of the IPSM
/// paraboloid (`point_rtw`, one side and two): the GPU mask (casters refined on the
/// GPU, warped depth pass and lookup) equals eval's CPU mask on all
/// but 0.1% of the pixels both classify (the rest are silhouette pixels, where the
/// rasterized and the ray-traced primary surface differ).
#[test]
fn rtw_over_spot_and_paraboloid_bases_matches_the_cpu_reference() {
    let Some(ctx) = shadowmap_wgpu::context::test_context(
        "rtw_over_spot_and_paraboloid_bases_matches_the_cpu_reference",
    ) else {
        return;
    };
    let cases = [
        ("facing_spot", TechniqueKind::SpotRtw),
        ("point_mid", TechniqueKind::PointRtw),
        ("point_inside", TechniqueKind::PointRtw),
        ("point_far", TechniqueKind::PointRtw),
        ("point_mid", TechniqueKind::CubeRtw),
        ("point_inside", TechniqueKind::CubeRtw),
        ("facing_point", TechniqueKind::CubeRtw),
    ];
    let mut renderer = HeadlessRenderer::new();
    for (name, kind) in cases {
        let config = configuration(name);
        let frame = ReportFrame::new(&config);
        let (cpu, gpu) = frame.masks(&ctx, &mut renderer, kind, 1024 * 1024);
        assert_masks_agree(name, kind, &cpu, &gpu);
    }
}

/// Tiled cube maps (`cube_tiled`: every tile drawn into its square of the atlas,
/// the lookup's face, cell and tile): the GPU mask equals eval's CPU mask (each tile
/// rasterized on its own) on all but 0.1% of the pixels both classify, with the
/// light among the buildings, above the street and facing the camera.
#[test]
fn tiled_cube_maps_match_the_cpu_reference() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("tiled_cube_maps_match_the_cpu_reference")
    else {
        return;
    };
    let mut renderer = HeadlessRenderer::new();
    for name in ["point_near", "point_mid", "facing_point"] {
        let config = configuration(name);
        let frame = ReportFrame::new(&config);
        let kind = TechniqueKind::CubeTiled;
        let (cpu, gpu) = frame.masks(&ctx, &mut renderer, kind, 1024 * 1024);
        assert_masks_agree(name, kind, &cpu, &gpu);
    }
}

/// The GPU mask equals the CPU mask on all but 0.1% of the pixels both classify,
/// over a quarter of the frame at least, and neither is trivial.
fn assert_masks_agree(name: &str, kind: TechniqueKind, cpu: &CpuMask, gpu: &ShadowMask) {
    let both: Vec<(bool, bool)> = gpu
        .values
        .iter()
        .zip(&cpu.lit)
        .filter_map(|(g, c)| Some((g.lit()?, (*c)?)))
        .collect();
    let differing = both.iter().filter(|(g, c)| g != c).count();
    let shadowed = both.iter().filter(|(_, c)| !c).count();
    eprintln!(
        "{} on {name}: {differing} of {} pixels differ ({:.3}%), {shadowed} shadowed",
        kind.name(),
        both.len(),
        100.0 * differing as f64 / both.len().max(1) as f64
    );
    assert!(
        both.len() > (W * H / 4) as usize,
        "{name}: {} pixels",
        both.len()
    );
    assert!(
        shadowed > both.len() / 100 && shadowed < both.len() * 99 / 100,
        "{name}: a trivial mask"
    );
    assert!(
        differing as f64 <= 1e-3 * both.len() as f64,
        "{name}: {differing} pixels differ"
    );
}

/// Mask side of the projective shadows.
const MASK_SIDE: u32 = 2048;

/// Projective shadows of the scene's closed parts (occluders) on its open parts
/// (receivers), GPU against the CPU reference of the same algorithm; returns the
/// number of differing pixels.
fn projective_vs_cpu(ctx: &GpuContext, name: &str, config: &Configuration) -> usize {
    let (scene, camera, light) = (&config.scene, config.camera(), &config.light);
    let tris = scene.mesh.triangles_f32();
    let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
    let indices: Vec<[u32; 3]> = (0..tris.len() as u32)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    let part = Partition::new(&positions, &indices).unwrap();
    let mut is_occluder = vec![false; tris.len()];
    for t in &part.closed {
        is_occluder[t[0] as usize / 3] = true;
    }
    let pick = |list: &[[u32; 3]]| -> Vec<[Vec3; 3]> {
        list.iter()
            .map(|t| t.map(|k| positions[k as usize]))
            .collect()
    };
    let (occluders, receivers) = (pick(&part.closed), pick(&part.open));
    let bounds = Aabb::from_points(&occluders.concat()).unwrap();
    let shadow = ProjectiveShadow::new(light, &bounds).unwrap();
    let reference = OccluderMask::render(&shadow, &positions, &part.closed, MASK_SIDE).unwrap();
    let bvh = Bvh::build(&scene.mesh).unwrap();
    let gbuffer = GBuffer::trace(&bvh, camera, W, H).unwrap();
    let cpu: Vec<Option<bool>> = gbuffer
        .surfaces
        .iter()
        .map(|s| {
            s.map(|s| is_occluder[s.triangle] || !reference.shadows(&shadow, s.position.as_vec3()))
        })
        .collect();
    let gpu = ProjectiveRenderer::new()
        .render_mask(
            ctx,
            (&receivers, &occluders),
            camera,
            &shadow,
            MASK_SIDE,
            (W, H),
        )
        .unwrap();
    let diff = gpu
        .values
        .iter()
        .zip(&cpu)
        .filter(|(g, c)| g.lit() != **c)
        .count();
    let shadowed = cpu.iter().filter(|c| **c == Some(false)).count();
    eprintln!(
        "{name} projective: {diff} of {} pixels differ ({:.3}%); shadowed {shadowed}",
        W * H,
        100.0 * diff as f64 / f64::from(W * H)
    );
    assert!(shadowed > 1000, "{name}: no shadows on the receivers");
    diff
}

#[test]
fn projective_shadows_match_the_cpu_reference() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("projective_shadows_match_the_cpu_reference")
    else {
        return;
    };
    for name in ["grazing", "top_down"] {
        let diff = projective_vs_cpu(&ctx, name, &configuration(name));
        assert_close(name, diff);
    }
}

#[test]
fn gpu_silhouette_is_the_cpu_silhouette() {
    let Some(ctx) = shadowmap_wgpu::context::test_context("gpu_silhouette_is_the_cpu_silhouette")
    else {
        return;
    };
    for name in ["facing_spot", "point_inside", "behind"] {
        let config = configuration(name);
        let scene = VolumeScene::new(&config.scene.mesh.triangles_f32()).unwrap();
        let gpu = GpuSilhouette::new(&ctx, scene.casters()).unwrap();
        let mut found = gpu.find(&ctx, &config.light).unwrap();
        // The CPU reference, through the volume renderer's own update.
        let mut volume = shadowmap_volume::ShadowVolume::new();
        volume.update(scene.casters(), &config.light).unwrap();
        let mut expected = volume.silhouette.clone();
        found.sort_unstable();
        expected.sort_unstable();
        eprintln!(
            "{name}: {} silhouette edges on the GPU, {} on the CPU",
            found.len(),
            expected.len()
        );
        assert!(!expected.is_empty());
        assert_eq!(found, expected, "{name}");
    }
}

/// One renderer kept across frames (its attachments, uniform and vertex buffers are
/// reused) renders what a fresh renderer renders, when the scene, the light, the size
/// and the method change between frames and when a frame repeats.
#[test]
fn a_reused_volume_renderer_renders_what_a_fresh_one_does() {
    let Some(ctx) = shadowmap_wgpu::context::test_context(
        "a_reused_volume_renderer_renders_what_a_fresh_one_does",
    ) else {
        return;
    };
    let (city, room) = (configuration("behind"), configuration("point_inside"));
    let mut scenes = [city.clone(), room.clone()]
        .map(|c| VolumeScene::new(&c.scene.mesh.triangles_f32()).unwrap());
    let mut reused = VolumeRenderer::new();
    let frames = [
        (0, &city, (W, H), VolumeMethod::ZPass),
        (1, &room, (W, H), VolumeMethod::ZFail),
        (1, &room, (W, H), VolumeMethod::ZFail),
        (0, &city, (W / 2, H / 3), VolumeMethod::ZFail),
        (0, &city, (W, H), VolumeMethod::ZPass),
    ];
    for (scene, config, size, method) in frames {
        let mut render = |renderer: &mut VolumeRenderer| {
            renderer
                .render_mask(
                    &ctx,
                    &mut scenes[scene],
                    config.camera(),
                    &config.light,
                    size,
                    method,
                )
                .unwrap()
        };
        let fresh = render(&mut VolumeRenderer::new());
        let kept = render(&mut reused);
        assert_eq!((kept.width, kept.height), size);
        assert!(
            kept.values.contains(&MaskValue::Shadowed),
            "{}: no shadow",
            config.name
        );
        assert!(
            kept == fresh,
            "{} {size:?} {method:?}: the reused renderer differs",
            config.name
        );
    }
}

/// The renderer's default biases on perspective depth, against the volumes: a cube
/// face (or a spot map) stores depth from a near plane close to the light, where 1e-4
/// of stored depth spans metres a hundred metres away, so a lookup bias in those
/// units lit whole walls turned away from the light (cube maps 27.9%, the spot fit
/// 17.3% of this frame misclassified). With the defaults, cube maps, RTW over their
/// faces and the spot maps differ from the volumes on shadow edges only (under 10%
/// of the pixels at this resolution, as IPSM, whose depth is linear).
#[test]
fn default_biases_keep_perspective_maps_with_the_volumes() {
    let Some(ctx) = shadowmap_wgpu::context::test_context(
        "default_biases_keep_perspective_maps_with_the_volumes",
    ) else {
        return;
    };
    let scene = Scene::city_block(1);
    let tris = scene.mesh.triangles_f32();
    let fov = 55f32.to_radians();
    let camera = Camera::look_at(
        Vec3::new(-20.0, 25.0, 110.0),
        Vec3::ZERO,
        Vec3::Y,
        Projection::perspective(fov, 16.0 / 9.0, 1.0, 400.0),
    )
    .unwrap();
    // A lamp and a spot among the buildings, at the same place.
    let position = Vec3::new(5.0, 40.0, 10.0);
    let lamp = Light::Point {
        position,
        range: 600.0,
    };
    let spot = Light::Spot {
        position,
        direction: Vec3::new(-0.2, -1.0, 0.6).normalize(),
        half_angle: 0.9,
        range: 600.0,
    };
    let gbuffer = GBuffer::trace(&Bvh::build(&scene.mesh).unwrap(), &camera, W / 2, H / 2).unwrap();
    let samples = eye_samples(&gbuffer, &camera);
    let pixels_per_radian = (H / 2) as f32 / 2.0 / (fov / 2.0).tan();
    let mut volumes = VolumeScene::new(&tris).unwrap();
    let mut exact = VolumeRenderer::new();
    let bounds = scene.scene_bounds().unwrap();
    let options = RenderOptions::default()
        .with_size(W, H)
        .with_filter(ShadowFilter::Pcf {
            taps: 3,
            radius: 1.0,
        });
    let mut renderer = HeadlessRenderer::new();
    let rtw = shadowmap::RtwPlan::default();
    for (light, techniques) in [
        (
            &lamp,
            vec![
                shadowmap::Technique::Ipsm(Default::default()),
                shadowmap::Technique::CubeMaps(Default::default()),
                shadowmap::Technique::CubeRtw {
                    cube: Default::default(),
                    rtw,
                },
            ],
        ),
        (
            &spot,
            vec![
                shadowmap::Technique::SpotFit { reversed_z: false },
                shadowmap::Technique::SpotWarp(Default::default()),
                shadowmap::Technique::SpotRtw(rtw),
            ],
        ),
    ] {
        let truth = exact
            .render_mask(
                &ctx,
                &mut volumes,
                &camera,
                light,
                (W, H),
                VolumeMethod::ZFail,
            )
            .unwrap();
        for technique in techniques {
            let input = shadowmap::FitInput::new(&camera, light, bounds, 1024 * 1024)
                .with_eye_samples(&samples)
                .with_pixels_per_radian(pixels_per_radian);
            let shadow = shadowmap::fit(&technique, &input).unwrap();
            let frame = renderer
                .render_shadow(&ctx, &tris, &camera, &shadow, &options)
                .unwrap();
            let (miss, _) = misclassification(&frame.mask, &truth);
            eprintln!(
                "{} with the default biases: {:.3}% misclassified ({} falsely lit, {} falsely shadowed)",
                technique.name(),
                100.0 * miss.rate(),
                miss.false_lit,
                miss.false_shadowed
            );
            assert!(miss.rate() < 0.1, "{}: {}", technique.name(), miss.rate());
        }
    }
}
