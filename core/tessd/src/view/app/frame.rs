//! One frame: what background work finished, the script's actions, every item rendered and
//! composited by depth, the heads-up text, and the picture presented.

use super::*;

impl Viewer {
    /// Draws one frame. Returns false to quit.
    pub(super) fn frame(&mut self, _: &ActiveEventLoop) -> Result<bool> {
        let start = Instant::now();
        if let Some(last) = self.last_start.replace(start) {
            self.stats
                .frame_ms
                .push(start.duration_since(last).as_secs_f64() * 1e3);
            if self.busy() {
                self.stats.frames_while_busy += 1;
            }
        }
        self.take_background()?;
        let mut shots = Vec::new();
        let go_on = self.run_script(&mut shots)?;
        if self.playing && !self.frames.is_empty() {
            self.frame_index = (self.frame_index + 1) % self.frames.len();
            self.show_frame()?;
        }
        let (w, h) = self.presenter.size();
        self.settings.width = w;
        self.settings.height = h;
        self.nav.camera = self.nav.camera.clipped_to(&self.nav.bounds);
        // the .tsc workers refine for the camera as it is now
        for t in &mut self.tsc {
            let c = &self.nav.camera;
            t.refinement.request(tessd_codec::Camera {
                eye: c.eye.to_array(),
                target: c.target.to_array(),
                up: c.up.to_array(),
                fov: c.fov,
                width: w,
                height: h,
            });
        }
        // the first item's frame is the picture; the others are composited over it by depth
        let mut picture: Option<Frame> = None;
        let mut offset = 0u32;
        for item in &mut self.items {
            let drawn = item.render(
                &self.renderer,
                &self.nav.camera,
                &self.settings,
                self.cracks,
            )?;
            match (&mut picture, drawn) {
                (None, Some(f)) => picture = Some(f),
                (Some(p), Some(f)) => items::composite(p, &f, offset),
                (_, None) => {}
            }
            offset += item_faces(item);
        }
        // nothing drawn yet (a .tsc's first view on its way): the renderer's background
        let frame = picture.unwrap_or_else(|| {
            let n = (w * h) as usize;
            Frame {
                width: w,
                height: h,
                color: tessd_render::surface::BACKGROUND.repeat(n),
                depth: vec![f32::INFINITY; n],
                face_id: vec![0; n],
                uv: vec![[0.0; 2]; n],
            }
        });
        let mut shown = frame.color.clone();
        self.last_frame = Some(frame);
        let mut lines = self.hud_lines();
        lines.extend(self.messages.iter().cloned());
        let mut canvas = Canvas {
            rgba: &mut shown,
            width: w as usize,
            height: h as usize,
        };
        canvas.block(0, &lines);
        if self.help {
            let help: Vec<String> = HELP.iter().map(|s| s.to_string()).collect();
            canvas.block(h as usize / 3, &help);
        }
        for shot in shots {
            self.screenshot(&shot.color, shot.face_ids.as_deref())?;
            if shot.overlay {
                tessd_render::image::write_png(&shot.color, w, h, &shown)?;
            }
        }
        self.presenter
            .present(self.renderer.context(), w, h, &shown)?;
        Ok(go_on)
    }

    /// The heads-up lines: what is drawn and how, each B-Rep part's steps, each `.tsc`'s
    /// reading.
    pub(super) fn hud_lines(&self) -> Vec<String> {
        let last = self.stats.frame_ms.last().copied().unwrap_or(0.0);
        let mut lines = vec![format!(
            "{} tris  {}  {}{}  subdiv {}  LOD {}  {last:.0} ms/frame  (H: keys)",
            self.triangles(),
            self.settings.mode.name(),
            self.settings.shading.name(),
            if self.settings.edges { "+edges" } else { "" },
            self.shown_level,
            self.lod,
        )];
        let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
        for item in &self.items {
            if let Item::Brep(b) = item {
                let t = &b.report.timings;
                lines.push(format!(
                    "B-Rep {} faces, cracks {}: tessellate {:.1}  trim {:.1}  detect {:.1}  fill {:.1} ms",
                    b.faces,
                    self.cracks.name(),
                    ms(t.tessellation),
                    ms(t.initial),
                    ms(t.crack_detection),
                    ms(t.image_fill + t.depth_mask + t.object_fill + t.composite),
                ));
            }
        }
        for t in &self.tsc {
            let r = &t.refinement;
            lines.push(format!(
                "tsc: {} bytes read, {} cells, {} triangles shown{}",
                r.bytes_read,
                r.cells,
                self.items[t.item].triangles(),
                if r.in_flight > 0 { ", refining" } else { "" }
            ));
        }
        lines
    }

    /// Applies what the background work finished.
    pub(super) fn take_background(&mut self) -> Result<()> {
        for done in self.background.poll() {
            match done {
                Done::Subdivided {
                    item,
                    level,
                    mesh,
                    scheme,
                    device,
                    topology_built,
                    frame,
                    ms,
                } => {
                    self.topologies += u64::from(topology_built);
                    if level != self.level {
                        continue;
                    }
                    if let Some(Item::Mesh(m)) = self.items.get_mut(item) {
                        m.show(&mesh, &self.renderer)?;
                    }
                    self.shown_level = level;
                    self.subdiv_scheme = scheme;
                    self.subdiv_device = device;
                    let t = self.triangles();
                    if frame.is_none() || topology_built {
                        let phase = if topology_built {
                            "topology and apply"
                        } else {
                            "apply"
                        };
                        self.say(format!(
                            "subdivision {level} ({scheme}, {device}, {phase} {ms:.0} ms): {t} triangles"
                        ));
                    }
                }
                Done::Skipped => {}
                Done::Lods { item, levels, ms } => {
                    let n = levels.len();
                    if let Some(Item::Mesh(m)) = self.items.get_mut(item) {
                        m.lods = Some(levels);
                    }
                    self.say(format!("LOD chain built: {n} levels ({ms:.0} ms)"));
                    let step = std::mem::take(&mut self.lod_step_pending);
                    if step != 0 && !self.busy() {
                        self.step_lod(step)?;
                    }
                }
                Done::Refined {
                    item,
                    scene,
                    cells,
                    triangles,
                    bytes_read,
                    ms,
                } => {
                    if let Some(Item::Mesh(m)) = self.items.get_mut(item) {
                        m.show_scene(*scene, &self.renderer)?;
                    }
                    if let Some(t) = self.tsc.iter_mut().find(|t| t.item == item) {
                        let r = &mut t.refinement;
                        r.in_flight = 0;
                        r.views += 1;
                        r.bytes_read += bytes_read;
                        r.cells = cells;
                    }
                    self.say(format!(
                        "refined: {cells} cells, {triangles} triangles, {bytes_read} bytes read ({ms:.0} ms)"
                    ));
                }
                Done::Failed(why) => self.say(format!("failed: {why}")),
            }
        }
        Ok(())
    }
}

/// A screenshot a script asked for.
pub(super) struct Shot {
    pub(super) color: PathBuf,
    pub(super) face_ids: Option<PathBuf>,
    pub(super) overlay: bool,
}

/// Faces an item's ids run over (the next item's ids start after them).
pub(super) fn item_faces(item: &Item) -> u32 {
    match item {
        Item::Mesh(m) => m.face_ids,
        Item::Brep(b) => b.faces as u32,
    }
}
