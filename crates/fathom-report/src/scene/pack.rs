//! A page's scenes as one little-endian binary buffer of typed arrays (`f32`, `u32`,
//! `u8`, each 4-byte aligned so that the page views them without copying) and a
//! small JSON header naming each array's offset, length and type.

use serde_json::{Value, json};

use super::data::{Scene, ScenePage};

/// The packed page data.
#[derive(Debug, Clone, PartialEq)]
pub struct Packed {
    /// The header (title, scenes, array references `{o, n, t}`).
    pub header: Value,
    /// The arrays, one after the other.
    pub bytes: Vec<u8>,
}

#[derive(Default)]
struct Packer {
    bytes: Vec<u8>,
}

impl Packer {
    fn align(&mut self) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        self.bytes.len()
    }

    fn f32s(&mut self, v: impl IntoIterator<Item = f32>) -> Value {
        let o = self.align();
        let mut n = 0usize;
        for x in v {
            self.bytes.extend_from_slice(&x.to_le_bytes());
            n += 1;
        }
        json!({"o": o, "n": n, "t": "f32"})
    }

    fn u32s(&mut self, v: impl IntoIterator<Item = u32>) -> Value {
        let o = self.align();
        let mut n = 0usize;
        for x in v {
            self.bytes.extend_from_slice(&x.to_le_bytes());
            n += 1;
        }
        json!({"o": o, "n": n, "t": "u32"})
    }

    fn u8s(&mut self, v: impl IntoIterator<Item = u8>) -> Value {
        let o = self.align();
        let before = self.bytes.len();
        self.bytes.extend(v);
        json!({"o": o, "n": self.bytes.len() - before, "t": "u8"})
    }

    fn points(&mut self, v: &[[f32; 3]]) -> Value {
        self.f32s(v.iter().flatten().copied())
    }
}

fn distance(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f32>()
        .sqrt()
}

fn scene_header(p: &mut Packer, s: &Scene) -> Value {
    let m = &s.mesh;
    let t0 = s.times.first().copied().unwrap_or(0.0);
    // Times relative to the first epoch, so that f32 keeps sub-millisecond steps.
    let rel = |t: f64| (t - t0) as f32;
    let methods: Vec<Value> = s
        .methods
        .iter()
        .map(|t| {
            json!({
                "name": t.name,
                "modes": t.mode_names,
                "pos": p.points(&t.positions),
                "mode": p.u8s(t.mode.iter().copied()),
                "err": p.f32s(t.positions.iter().zip(&s.truth).map(|(e, x)| distance(e, x))),
            })
        })
        .collect();
    json!({
        "name": s.name,
        "t0": t0,
        "styles": m.styles.iter().map(|st| json!({
            "name": st.name, "color": st.color, "opacity": st.opacity,
        })).collect::<Vec<_>>(),
        "mesh": {
            "v": p.points(&m.vertices),
            "i": p.u32s(m.triangles.iter().flatten().copied()),
            "m": p.u8s(m.material.iter().copied()),
        },
        "times": p.f32s(s.times.iter().map(|&t| rel(t))),
        "truth": p.points(&s.truth),
        "methods": methods,
        "scans": {
            "t": p.f32s(s.scans.iter().map(|x| rel(x.time))),
            "o": p.f32s(s.scans.iter().flat_map(|x| x.origin)),
            "n": p.u32s(s.scans.iter().map(|x| x.hits.len() as u32)),
            "h": p.f32s(s.scans.iter().flat_map(|x| x.hits.iter().flatten().copied())),
        },
        "sky": {
            "t": p.f32s(s.sky.iter().map(|x| rel(x.time))),
            "n": p.u32s(s.sky.iter().map(|x| x.sats.len() as u32)),
            "d": p.f32s(s.sky.iter().flat_map(|x| x.sats.iter().flat_map(|(d, _)| *d))),
            "v": p.u8s(s.sky.iter().flat_map(|x| x.sats.iter().map(|(_, v)| u8::from(*v)))),
        },
    })
}

/// Packs a page's (already thinned) scenes.
pub fn pack(page: &ScenePage) -> Packed {
    let mut p = Packer::default();
    let scenes: Vec<Value> = page
        .scenes
        .iter()
        .map(|s| scene_header(&mut p, s))
        .collect();
    Packed {
        header: json!({
            "title": page.title,
            "note": page.note,
            "frame": "NED metres; the page draws east right, up up, north into the screen",
            "scenes": scenes,
        }),
        bytes: p.bytes,
    }
}

#[cfg(test)]
mod tests {
    use super::super::data::tests_support::small_scene;
    use super::*;

    fn f32_at(bytes: &[u8], r: &Value, k: usize) -> f32 {
        let o = r["o"].as_u64().unwrap() as usize + 4 * k;
        f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap())
    }

    /// Arrays are 4-byte aligned and hold the values the header says, and the error
    /// series is the distance of estimate and truth.
    #[test]
    fn arrays_round_trip_through_the_header() {
        let page = ScenePage {
            title: "t".into(),
            note: String::new(),
            scenes: vec![small_scene()],
        };
        let p = pack(&page);
        let s = &p.header["scenes"][0];
        for r in [
            &s["mesh"]["v"],
            &s["mesh"]["i"],
            &s["mesh"]["m"],
            &s["truth"],
        ] {
            assert_eq!(r["o"].as_u64().unwrap() % 4, 0);
        }
        assert_eq!(s["mesh"]["v"]["n"], 9);
        assert_eq!(f32_at(&p.bytes, &s["mesh"]["v"], 3), 1.0);
        let m = &s["methods"][0];
        assert_eq!(m["mode"]["n"], 2);
        let o = m["mode"]["o"].as_u64().unwrap() as usize;
        assert_eq!(&p.bytes[o..o + 2], &[0, 1]);
        assert!((f32_at(&p.bytes, &m["err"], 1) - 0.1).abs() < 1e-6);
        assert_eq!(f32_at(&p.bytes, &s["times"], 1), 1.0);
    }
}
