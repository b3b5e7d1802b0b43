#![no_main]
//! Fuzzes `shadowmap-volume`: the closed-mesh check, the partition into closed and
//! open parts, and the shadow volume of any mesh that passes, for any light. Bad
//! input must be a typed error; a volume must be finite where `w = 1`, made of whole
//! triangles, with a silhouette of closed loops.

use libfuzzer_sys::fuzz_target;
use shadowmap_frustum::Light;
use shadowmap_frustum::glam::Vec3;
use shadowmap_testgen::arbitrary::{Result, Unstructured};
use shadowmap_volume::{EdgeMesh, Partition, ShadowVolume};

fn vec3(u: &mut Unstructured<'_>) -> Result<Vec3> {
    // Small integer grids weld often and make closed meshes reachable.
    if u.arbitrary::<bool>()? {
        let k = |v: i8| f32::from(v % 4);
        Ok(Vec3::new(k(u.arbitrary()?), k(u.arbitrary()?), k(u.arbitrary()?)))
    } else {
        Ok(Vec3::new(u.arbitrary()?, u.arbitrary()?, u.arbitrary()?))
    }
}

fn light(u: &mut Unstructured<'_>) -> Result<Light> {
    Ok(match u.int_in_range(0..=2u8)? {
        0 => Light::Directional { direction: vec3(u)? },
        1 => Light::Point { position: vec3(u)?, range: u.arbitrary()? },
        _ => Light::Spot {
            position: vec3(u)?,
            direction: vec3(u)?,
            half_angle: u.arbitrary()?,
            range: u.arbitrary()?,
        },
    })
}

fn run(u: &mut Unstructured<'_>) -> Result<()> {
    let n = u.int_in_range(0..=24usize)?;
    let positions = (0..n).map(|_| vec3(u)).collect::<Result<Vec<_>>>()?;
    let m = u.int_in_range(0..=32usize)?;
    let bound = u32::try_from(n).unwrap_or(0) + 1;
    let indices = (0..m)
        .map(|_| Ok([0; 3].map(|_| u.int_in_range(0..=bound).unwrap_or(0))))
        .collect::<Result<Vec<_>>>()?;
    let light = light(u)?;
    if let Ok(part) = Partition::new(&positions, &indices) {
        // The closed parts are closed on their own.
        if let Err(e) = EdgeMesh::new(&positions, &part.closed) {
            panic!("closed part refused: {e}");
        }
    }
    let Ok(mesh) = EdgeMesh::new(&positions, &indices) else {
        return Ok(());
    };
    assert_eq!(mesh.edges.len() * 2, mesh.triangle_count() * 3);
    let mut volume = ShadowVolume::new();
    if volume.update(&mesh, &light).is_err() {
        return Ok(());
    }
    assert_eq!(volume.vertices.len() % 3, 0);
    assert!(volume.vertices.iter().all(|v| v.is_finite()));
    let mut degree = vec![0i32; mesh.positions.len()];
    for &[a, b] in &volume.silhouette {
        degree[a as usize] += 1;
        degree[b as usize] -= 1;
    }
    assert!(degree.iter().all(|&d| d == 0), "silhouette is not closed loops");
    Ok(())
}

fuzz_target!(|data: &[u8]| {
    let _ = run(&mut Unstructured::new(data));
});
