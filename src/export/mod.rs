//! Scenes written for other renderers: scene.toml --scene::load--> Scene --export--> a peer's
//! scene file. `mitsuba`: Mitsuba 3 XML, with meshes as PLY files beside it (`chambre export
//! --mitsuba`). What a peer cannot express is refused by name, placed in the scene file, unless
//! the caller asks for the nearest it has (`approximate`), which is then listed. The mapping and
//! its reasons: `docs/mitsuba.md`.

mod files;
pub mod mitsuba;

pub use mitsuba::{MitsubaExport, MitsubaIntegrator, MitsubaOptions, to_mitsuba, write_mitsuba};
