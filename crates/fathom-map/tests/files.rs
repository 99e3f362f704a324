//! Real mesh files read in tests (`tests/data/`): an OBJ as a GIS tool exports it
//! (Z-up ENU with a UTM-like origin offset, `usemtl` materials, groups, a polygon,
//! texture and normal indices, a duplicate and a degenerate face) and the same wedge
//! as binary and ASCII STL; then the same files broken (truncated, NaN vertex, index
//! out of range, unknown material): errors name the file and the line or face.

use fathom_core::{Material, RayCaster};
use fathom_map::{AxisConvention, BvhCaster, ImportSettings, MaterialTable, obj, stl};
use nalgebra::Vector3;

const HOUSE: &str = include_str!("data/house.obj");
const WEDGE_BINARY: &[u8] = include_bytes!("data/wedge_binary.stl");
const WEDGE_ASCII: &str = include_str!("data/wedge_ascii.stl");

fn house_settings() -> ImportSettings {
    let mut materials = MaterialTable::default();
    materials
        .insert("concrete", Material::Opaque)
        .insert("roof_tiles", Material::Other(1));
    ImportSettings {
        axes: AxisConvention::EnuZUp,
        origin_offset: [325_000.0, 4_150_000.0, 0.0],
        materials,
        default_material: None,
        ..ImportSettings::default()
    }
}

/// 1-based number of the first line containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn a_gis_obj_with_materials_reads_into_local_ned() {
    let (mesh, report) = obj::read_obj(HOUSE.as_bytes(), &house_settings()).unwrap();
    assert_eq!(report.faces_read, 11);
    assert_eq!(report.polygons_triangulated, 7);
    assert_eq!(report.mesh.triangles_in, 18);
    assert_eq!(report.mesh.duplicate_skipped, 1);
    assert_eq!(report.mesh.degenerate_skipped, 1);
    assert_eq!(mesh.len(), 16);
    let map = BvhCaster::new(&mesh);
    // from 10 m south of the house, 3 m up, looking north: the glass front at 10 m
    let hit = map
        .cast(&Vector3::new(-10.0, 5.0, -3.0), &Vector3::x(), 100.0)
        .unwrap();
    assert!((hit.range - 10.0).abs() < 1e-9);
    assert_eq!(hit.material, Material::Glass);
    // from 20 m up over the ridge, looking down: the roof (9 m high) at 11 m
    let hit = map
        .cast(&Vector3::new(4.0, 5.0, -20.0), &Vector3::z(), 100.0)
        .unwrap();
    assert!((hit.range - 11.0).abs() < 1e-9);
    assert_eq!(hit.material, Material::Other(1));
    // from the west at 3 m height: the concrete west wall at east = 0
    let hit = map
        .cast(&Vector3::new(4.0, -7.0, -3.0), &Vector3::y(), 100.0)
        .unwrap();
    assert!((hit.range - 7.0).abs() < 1e-9);
    assert_eq!(hit.material, Material::Opaque);
    // the ground (lot) is concrete at z = 0
    let hit = map
        .cast(&Vector3::new(-5.0, -5.0, -1.0), &Vector3::z(), 100.0)
        .unwrap();
    assert!((hit.range - 1.0).abs() < 1e-9);
}

#[test]
fn binary_and_ascii_stl_read_the_same_wedge() {
    let settings = ImportSettings {
        axes: AxisConvention::Ned,
        default_material: Some(Material::Glass),
        ..ImportSettings::default()
    };
    assert_eq!(stl::stl_kind(WEDGE_BINARY).unwrap(), stl::StlKind::Binary);
    assert_eq!(
        stl::stl_kind(WEDGE_ASCII.as_bytes()).unwrap(),
        stl::StlKind::Ascii
    );
    let (bin, rb) = stl::read_stl(WEDGE_BINARY, &settings).unwrap();
    let (asc, ra) = stl::read_stl(WEDGE_ASCII.as_bytes(), &settings).unwrap();
    assert_eq!((rb.faces_read, ra.faces_read), (8, 8));
    assert_eq!(rb.mesh.boundary_edges, 0); // closed
    assert_eq!(bin, asc);
    assert!(bin.materials().iter().all(|&m| m == Material::Glass));
    // the slanted face x + 2 y = 2 seen from (2, 2) along -(1, 2)/sqrt(5)
    let map = BvhCaster::new(&bin);
    let d = -Vector3::new(1.0, 2.0, 0.0).normalize();
    let hit = map.cast(&Vector3::new(2.0, 2.0, -0.5), &d, 10.0).unwrap();
    assert!((hit.range - 4.0 / 5f64.sqrt()).abs() < 1e-6);
}

#[test]
fn broken_files_name_the_file_and_the_line_or_face() {
    let s = house_settings();
    let err = |text: &str| {
        obj::read_obj(text.as_bytes(), &s)
            .unwrap_err()
            .in_file("house.obj")
            .to_string()
    };
    // truncated in the middle of a vertex line
    let cut = &HOUSE[..HOUSE.find("v 325010.0 4150004.0").unwrap() + 14];
    assert_eq!(
        err(cut),
        format!(
            "`house.obj`: OBJ line {}: position parse error",
            line_of(HOUSE, "v 325010.0 4150004.0")
        )
    );
    // a NaN vertex
    let nan = HOUSE.replace("v 325010.0 4150008.0 6.0", "v 325010.0 NaN 6.0");
    assert_eq!(
        err(&nan),
        format!(
            "`house.obj`: OBJ line {}: vertex coordinate NaN (NED, m) is not finite or beyond +-1000000000 m",
            line_of(HOUSE, "v 325010.0 4150008.0 6.0")
        )
    );
    // a face index out of range
    let far = HOUSE.replace("f 10 11 14\nf 9 9 10", "f 10 11 14\nf 9 9 99");
    assert_eq!(
        err(&far),
        format!(
            "`house.obj`: OBJ line {}: vertex index 99 out of range (14 defined before this line)",
            line_of(HOUSE, "f 9 9 10")
        )
    );
    // an unknown material
    let unknown = HOUSE.replace("usemtl roof_tiles", "usemtl slate");
    assert_eq!(
        err(&unknown),
        format!(
            "`house.obj`: OBJ line {}: unknown material `slate` (map it in the import settings' material table)",
            line_of(HOUSE, "usemtl roof_tiles")
        )
    );
    // STL: truncated in face 5, a NaN in face 2, ASCII cut in face 3
    let ned = ImportSettings {
        axes: AxisConvention::Ned,
        ..ImportSettings::default()
    };
    let stl_err = |bytes: &[u8]| {
        stl::parse_stl(bytes, &ned)
            .unwrap_err()
            .in_file("wedge.stl")
            .to_string()
    };
    assert!(
        stl_err(&WEDGE_BINARY[..84 + 50 * 5 + 17])
            .starts_with("`wedge.stl`: STL face 5: binary STL truncated")
    );
    let mut nan = WEDGE_BINARY.to_vec();
    let at = 84 + 50 * 2 + 12 + 4 * 4; // face 2, second vertex, y
    nan[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    assert!(stl_err(&nan).starts_with("`wedge.stl`: STL face 2: vertex 1: coordinate NaN"));
    let lines: Vec<&str> = WEDGE_ASCII.lines().collect();
    let cut = lines[..1 + 7 * 3 + 4].join("\n");
    assert!(
        stl_err(cut.as_bytes()).starts_with("`wedge.stl`: STL face 3:"),
        "{}",
        stl_err(cut.as_bytes())
    );
}
