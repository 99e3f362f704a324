//! A world mesh in the scene page's form ([`fathom_report::scene::SceneMesh`]): the
//! styles of its materials and the vertices as `f32` (the `urban` experiment's, the
//! PILS session's and the `gnss-ins` replay's pages draw worlds the same way).

use fathom_core::Material;
use fathom_map::TriMesh;
use fathom_report::scene::{MaterialStyle, SceneMesh};

/// How a material is drawn: opaque grey, glass light blue and translucent, other
/// materials by their number.
pub fn style(m: Material) -> MaterialStyle {
    let (name, color, opacity) = match m {
        Material::Opaque => ("opaque".to_string(), 0x9da3ab, 1.0),
        Material::Glass => ("glass".to_string(), 0x7cc4ff, 0.35),
        Material::Other(id) => {
            let palette = [0xb5835a, 0x8c9a6b, 0xa97fb0, 0xc9b458, 0x6f8fa8];
            (
                format!("material {id}"),
                palette[usize::from(id) % palette.len()],
                1.0,
            )
        }
    };
    MaterialStyle {
        name,
        color,
        opacity,
    }
}

/// The mesh in the page's form: vertices as `f32`, one style per material present
/// (materials past the 256th share the last style).
pub fn mesh_of(mesh: &TriMesh) -> SceneMesh {
    let mut present: Vec<Material> = mesh.materials().to_vec();
    present.sort();
    present.dedup();
    present.truncate(256);
    let index = |m: &Material| {
        present
            .binary_search(m)
            .unwrap_or(present.len().saturating_sub(1)) as u8
    };
    SceneMesh {
        vertices: mesh
            .vertices()
            .iter()
            .map(|v| [v.x as f32, v.y as f32, v.z as f32])
            .collect(),
        triangles: mesh.triangles().to_vec(),
        material: mesh.materials().iter().map(index).collect(),
        styles: present.into_iter().map(style).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_map::MeshBuilder;
    use nalgebra::Vector3;

    /// Each material present gets one style (glass translucent, opaque not), every
    /// triangle points at its own material's style.
    #[test]
    fn mesh_styles_follow_the_materials() {
        let mut b = MeshBuilder::new();
        let v = |x: f64, y: f64| Vector3::new(x, y, 0.0);
        b.triangle_at(v(0.0, 0.0), v(1.0, 0.0), v(0.0, 1.0), Material::Glass);
        b.triangle_at(v(2.0, 0.0), v(3.0, 0.0), v(2.0, 1.0), Material::Opaque);
        b.triangle_at(v(4.0, 0.0), v(5.0, 0.0), v(4.0, 1.0), Material::Glass);
        let (mesh, _) = b.build().unwrap();
        let m = mesh_of(&mesh);
        assert_eq!(m.styles.len(), 2);
        for (t, mat) in mesh.materials().iter().enumerate() {
            let st = &m.styles[usize::from(m.material[t])];
            assert_eq!(st.name, mat.to_string());
            assert_eq!(st.opacity < 1.0, mat.is_glass());
        }
        assert_eq!(m.vertices.len(), mesh.vertices().len());
    }
}
