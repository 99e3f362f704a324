//! The GNSS / INS replay as a job of the runner ([`GnssIns`], experiment
//! `gnss-ins`): `fathom replay gnss-ins DIR`, `fathom replay ulog FILE.ulg` and
//! `fathom run` on its settings file go through the driver like every experiment
//! (module docs of [`crate::own_log`]). The `[data] dir` is a `gnss-ins` folder, or
//! a ULog file converted in memory exactly as `fathom log from-ulog` converts it.

use std::path::Path;

use rand_chacha::ChaCha8Rng;

use super::{GnssInsReplay, GnssInsSettings, GnssInsToml, analysis, figures, replay, report};
use crate::own_log::{self, GNSS_INS_PRESET, SEED_DOC, log_error};
use crate::world_file::read_mesh_file;
use fathom_data::layout::gnss_ins::GnssInsLog;
use fathom_data::layout::{FileSet, LogKind};
use fathom_map::TriMesh;
use fathom_sim::SimError;
use fathom_sim::cost::CostTerm;
use fathom_sim::experiment::{Analysis, Batch, Environment, Experiment};

/// The settings, the log's description and the log, read and checked.
#[derive(Debug)]
pub struct Prepared {
    settings: GnssInsSettings,
    /// The world mesh (in its file's frame) and what was read, with `[world]`.
    world: Option<(TriMesh, String)>,
    /// Whether a replay with a world writes `scene.html` (not with `--no-scene`).
    scene_page: bool,
    /// The log's description (its manifest's, or the ULog conversion's: the same
    /// text for the same flight).
    about: String,
    log: GnssInsLog,
}

/// A `gnss-ins` log from `path`: a folder in the layout, or a ULog file (converted in
/// memory); returns the log and its description.
///
/// # Errors
/// [`SimError::Input`] for a log that cannot be read (naming file, line, byte offset).
pub fn read_log(path: &Path) -> Result<(GnssInsLog, String), SimError> {
    if path.is_file() {
        let c = fathom_data::ulog::convert_file(path)
            .map_err(|e| SimError::Input(Box::new(SimError::model("reading the ULog", e))))?;
        let about = c.description(path);
        return Ok((c.log, about));
    }
    let set = FileSet::read_dir(path).map_err(log_error)?;
    set.expect_kind(LogKind::GnssIns).map_err(log_error)?;
    let log = GnssInsLog::parse(&set).map_err(log_error)?;
    Ok((log, set.manifest.description))
}

/// The `gnss-ins` replay of a drone flight.
#[derive(Debug, Clone, Copy, Default)]
pub struct GnssIns;

impl Experiment for GnssIns {
    type Scenario = GnssInsToml;
    type Checked = GnssInsSettings;
    type Prepared = Prepared;
    type Record = GnssInsReplay;
    type Kept = GnssInsReplay;
    type Fold = ();

    const NAME: &'static str = "gnss-ins";
    const SEED_DOC: &'static str = SEED_DOC;
    const DEFAULT_SCENARIO: &'static str = "scenarios/gnss-ins.toml";
    const PRESET: &'static str = GNSS_INS_PRESET;
    const ABOUT: &'static str = "GNSS / INS navigation of a drone flight (a PX4 ULog or a gnss-ins log): INS alone, the 12-state and 15-state GPS/INS filters, against PX4's EKF2 and, in simulation, the ground truth";
    const PAPER: bool = false;
    const CHECK_PREPARES: bool = true;

    fn check(&self, scenario: &GnssInsToml, file: &str) -> Result<GnssInsSettings, SimError> {
        scenario.check(file)
    }

    fn cost(&self, scenario: &GnssInsToml) -> Vec<CostTerm> {
        own_log::cost_terms(scenario.methods.len())
    }

    fn prepare(&self, settings: GnssInsSettings, env: &Environment) -> Result<Prepared, SimError> {
        let path = own_log::log_dir(env, &settings.data_dir);
        let (log, about) = read_log(&path)?;
        super::run::start_row(&log)?;
        let world = match &settings.world {
            None => None,
            Some(w) => {
                let beams = log
                    .range
                    .as_deref()
                    .unwrap_or(&[])
                    .iter()
                    .filter(|r| r.dir_in_body().is_some())
                    .count();
                if beams == 0 {
                    return Err(SimError::invalid_argument(
                        format!("world `{}`", fathom_core::echo::echo_file(&w.file)),
                        format!(
                            "the log `{}` has no range rows with a beam direction \
                             (`range.csv`): the map-aided filters need range beams; replay \
                             without --world",
                            fathom_core::echo::echo_path(&path)
                        ),
                    ));
                }
                Some(read_mesh_file(
                    &settings.file,
                    "world.file",
                    &w.file,
                    &env.base_dir,
                    &w.import,
                )?)
            }
        };
        Ok(Prepared {
            settings,
            world,
            scene_page: env.scene_page,
            about,
            log,
        })
    }

    fn batches(&self, _prepared: &Prepared) -> Vec<Batch> {
        vec![Batch::new(Self::NAME, 1)]
    }

    fn run(
        &self,
        p: &Prepared,
        _batch: usize,
        _index: usize,
        _rng: &mut ChaCha8Rng,
    ) -> Result<GnssInsReplay, SimError> {
        let mut r = replay(&p.log, &p.settings, p.world.as_ref().map(|w| &w.0))?;
        r.world = p.world.as_ref().map(|w| w.1.clone());
        Ok(r)
    }

    fn fold(
        &self,
        _prepared: &Prepared,
        _batch: usize,
        _index: usize,
        record: GnssInsReplay,
        _fold: &mut (),
    ) -> GnssInsReplay {
        record
    }

    fn analyse(
        &self,
        p: &Prepared,
        mut kept: Vec<Vec<GnssInsReplay>>,
        _folds: Vec<()>,
        out: &mut Analysis,
    ) -> Result<(), SimError> {
        let r = kept.first_mut().and_then(Vec::pop).ok_or_else(|| {
            SimError::invalid_argument("gnss-ins replay", "the replay did not run")
        })?;
        analysis::rows(&r, out);
        analysis::csv_files(&r, out)?;
        figures::write(&r, out)?;
        if let (Some((mesh, _)), true) = (&p.world, p.scene_page) {
            let title = format!("gnss-ins replay with the world {}", p.settings.world_file());
            out.page("scene.html", super::scene::page(&r, mesh, &title)?)?;
        }
        out.report(&report::notes(&r, &p.about));
        Ok(())
    }
}
