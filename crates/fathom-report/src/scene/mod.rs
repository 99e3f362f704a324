//! The 3D scene page (`scene.html`): a world mesh, the true and estimated paths with
//! their modes, range scans and satellite lines of sight over time, drawn by three.js
//! in one self-contained HTML file that opens from disk.
//!
//! | file | job |
//! | --- | --- |
//! | [`data`] | what a page shows ([`ScenePage`], [`Scene`]) and its checks |
//! | [`decimate`] | thinning for display (the reports keep every number) |
//! | [`pack`] | typed arrays in one binary buffer with a JSON header |
//! | [`page`] | the HTML: three.js, the viewer and the data inlined |

pub mod data;
pub mod decimate;
pub mod pack;
pub mod page;

pub use data::{MaterialStyle, MethodTrack, Scan, Scene, SceneMesh, ScenePage, SkyEpoch};
pub use page::scene_html;
