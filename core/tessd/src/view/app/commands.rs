//! The key commands (the help overlay's names; scripts press them too): views, draw modes,
//! subdivision levels, LODs and the partition, playing frames, screenshots.

use super::*;

impl Viewer {
    /// A key command, by the help overlay's names.
    pub(super) fn press(&mut self, name: &str) -> Result<()> {
        match name {
            "1" => self.nav.view(View::Front, self.aspect()),
            "3" => self.nav.view(View::Right, self.aspect()),
            "7" => self.nav.view(View::Top, self.aspect()),
            "9" => self.nav.opposite(),
            "5" => {
                self.nav.toggle_ortho();
                let look = if self.nav.ortho {
                    "orthographic"
                } else {
                    "perspective"
                };
                self.say(format!("camera {look}"));
            }
            "home" => self.nav.frame_all(self.aspect()),
            "w" => {
                let i = DrawMode::ALL.iter().position(|&m| m == self.settings.mode);
                let next = DrawMode::ALL[(i.unwrap_or(0) + 1) % DrawMode::ALL.len()];
                self.settings.mode = next;
                self.say(format!("mode {}", next.name()));
            }
            "e" => {
                self.settings.edges = !self.settings.edges;
                self.say(format!(
                    "edges {}",
                    if self.settings.edges { "on" } else { "off" }
                ));
            }
            "f" => {
                self.settings.shading = if self.settings.shading == Shading::FaceIds {
                    Shading::Lit
                } else {
                    Shading::FaceIds
                };
                self.say(format!("shading {}", self.settings.shading.name()));
            }
            "c" => {
                self.cracks = match self.cracks {
                    Cracks::None => Cracks::Image,
                    Cracks::Image => Cracks::Object,
                    Cracks::Object => Cracks::None,
                };
                self.say(format!("cracks {}", self.cracks.name()));
            }
            "h" => self.help = !self.help,
            "plus" => self.set_level((self.level + 1).min(MAX_LEVEL)),
            "minus" => self.set_level(self.level.saturating_sub(1)),
            "space" => {
                if self.frames.is_empty() {
                    self.say("no --frames to play".into());
                } else {
                    self.playing = !self.playing;
                    self.say(format!(
                        "frames {}",
                        if self.playing { "playing" } else { "paused" }
                    ));
                }
            }
            "f12" => {
                let path = self.screenshot_path();
                self.screenshot(&path, None)?;
            }
            "bracketleft" | "bracketright" => {
                let step: isize = if name == "bracketright" { 1 } else { -1 };
                self.step_lod(step)?;
            }
            "p" => {
                self.show_partition = !self.show_partition;
                self.show_lod()?;
            }
            other => self.say(format!("no command on key `{other}` (H lists the keys)")),
        }
        Ok(())
    }

    /// Asks for subdivision level `level` of every mesh item (the cage at 0), computed in the
    /// background, of the frame of `--frames` shown (if any).
    pub(super) fn set_level(&mut self, level: u32) {
        self.level = level;
        for i in 0..self.items.len() {
            let Item::Mesh(m) = &mut self.items[i] else {
                continue;
            };
            if self.tsc.iter().any(|t| t.item == i) {
                continue;
            }
            let frame = self
                .frames
                .get(self.frame_index)
                .filter(|_| self.playing || self.frame_index > 0);
            if level == 0 {
                let mesh = match frame {
                    Some(f) => with_positions(&m.cage, f),
                    None => (*m.cage).clone(),
                };
                let _ = m.show(&mesh, &self.renderer);
                self.shown_level = 0;
                continue;
            }
            let positions = match frame {
                Some(f) if f.positions.len() == m.cage.positions.len() => f.positions.clone(),
                _ => m.cage.positions.clone(),
            };
            let job = Job {
                item: i,
                level,
                cage: m.cage.clone(),
                positions,
                frame: frame.map(|_| self.frame_index),
            };
            self.background.subdivide(job);
        }
        if level == 0 {
            self.say(format!(
                "subdivision 0 (cage): {} triangles",
                self.triangles()
            ));
        }
    }

    /// Steps the LOD shown by `step` (the chain is built in the background on first use).
    pub(super) fn step_lod(&mut self, step: isize) -> Result<()> {
        let mut building = false;
        for (i, item) in self.items.iter().enumerate() {
            if let Item::Mesh(m) = item
                && m.lods.is_none()
                && !self.tsc.iter().any(|t| t.item == i)
            {
                let cage = m.cage.clone();
                self.background.spawn(move || lod_chain(i, cage));
                building = true;
            }
        }
        if building {
            self.say("building the LOD chain in the background".into());
            self.lod_step_pending = step;
            return Ok(());
        }
        let max = self
            .items
            .iter()
            .filter_map(|i| match i {
                Item::Mesh(m) => m.lods.as_ref().map(Vec::len),
                _ => None,
            })
            .max()
            .unwrap_or(0);
        self.lod = (self.lod as isize + step).clamp(0, max as isize) as usize;
        self.show_lod()
    }

    /// Shows LOD `self.lod` of every mesh item (0: the input, at the subdivision level asked
    /// for), with its partition when `P` is on.
    pub(super) fn show_lod(&mut self) -> Result<()> {
        let (lod, partition) = (self.lod, self.show_partition);
        for item in &mut self.items {
            let Item::Mesh(m) = item else { continue };
            let Some(lods) = m.lods.take() else { continue };
            let result = (|| -> Result<()> {
                if lod == 0 {
                    let cage = m.cage.clone();
                    m.show(&cage, &self.renderer)?;
                    // the input's partition is the first level's
                    let cells = lods.first().map(|l| l.1.as_slice()).filter(|_| partition);
                    m.show_partition(cells, &self.renderer)?;
                } else if let Some((mesh, cells)) = lods.get(lod - 1) {
                    m.show(mesh, &self.renderer)?;
                    m.show_partition(Some(cells.as_slice()).filter(|_| partition), &self.renderer)?;
                }
                Ok(())
            })();
            m.lods = Some(lods);
            result?;
        }
        self.shown_level = 0;
        let t = self.triangles();
        self.say(format!(
            "LOD {lod}{}: {t} triangles",
            if partition { " with its partition" } else { "" }
        ));
        Ok(())
    }

    /// Shows frame `frame_index` of `--frames` at the subdivision level asked for (its
    /// topology refined once, reused for every frame).
    pub(super) fn show_frame(&mut self) -> Result<()> {
        self.set_level(self.level);
        Ok(())
    }

    /// Where F12 saves: `<first input's stem>_view_NNN.png` beside it.
    pub(super) fn screenshot_path(&mut self) -> PathBuf {
        self.screenshots += 1;
        let first = self.items[0].path();
        let stem = first
            .file_stem()
            .map_or_else(|| "view".into(), |s| s.to_string_lossy().into_owned());
        first.with_file_name(format!("{stem}_view_{:03}.png", self.screenshots))
    }

    /// Writes the last frame's colour (and face ids) as `tessd render` does.
    pub(super) fn screenshot(&mut self, color: &Path, face_ids: Option<&Path>) -> Result<()> {
        let frame = self.last_frame.as_ref().context("no frame drawn yet")?;
        tessd_render::image::write_png(color, frame.width, frame.height, &frame.color)?;
        if let Some(p) = face_ids {
            let ids = tessd_render::image::face_ids_to_rgba(&frame.face_id);
            tessd_render::image::write_png(p, frame.width, frame.height, &ids)?;
        }
        self.say(format!("screenshot {}", color.display()));
        Ok(())
    }
}

/// `cage` with the positions of `frame` (same vertex count).
pub(super) fn with_positions(cage: &Mesh, frame: &Mesh) -> Mesh {
    let mut m = cage.clone();
    if frame.positions.len() == m.positions.len() {
        m.positions.clone_from(&frame.positions);
    }
    m
}
