//! `--script`'s actions between frames, and the statistics a `stats` action writes.

use super::frame::Shot;
use super::*;

impl Viewer {
    /// Runs the script's actions up to the next one that needs frames. Returns false to quit.
    pub(super) fn run_script(&mut self, shots: &mut Vec<Shot>) -> Result<bool> {
        if self.wait > 0 {
            self.wait -= 1;
            return Ok(true);
        }
        if self.until_idle {
            if self.busy() {
                return Ok(true);
            }
            self.until_idle = false;
        }
        while let Some(action) = self.script.get(self.next_action).cloned() {
            self.next_action += 1;
            match action {
                Action::Wait(n) => {
                    self.wait = n;
                    return Ok(true);
                }
                Action::Camera {
                    eye,
                    target,
                    up,
                    fov,
                } => {
                    let fov = fov.unwrap_or(self.nav.camera.fov);
                    self.nav
                        .set_camera(eye.into(), target.into(), up.into(), fov);
                }
                Action::Orbit(dx, dy) => self.nav.orbit(dx, dy),
                Action::Zoom(f) => self.nav.zoom(f),
                Action::Key(k) if k == "escape" => return Ok(false),
                Action::Key(k) => self.press(&k)?,
                Action::UntilIdle => {
                    self.until_idle = true;
                    return Ok(true);
                }
                Action::Screenshot {
                    color,
                    face_ids,
                    overlay,
                } => {
                    // taken from the frame drawn next, after the actions before it
                    shots.push(Shot {
                        color,
                        face_ids,
                        overlay,
                    });
                    return Ok(true);
                }
                Action::Stats(path) => {
                    let text = serde_json::to_string_pretty(&self.stats_json())?;
                    tessd_mesh::io::write_atomic(&path, |w| {
                        w.write_all(text.as_bytes())
                            .map_err(|source| tessd_mesh::MeshError::Io {
                                path: path.display().to_string(),
                                source,
                            })
                    })?;
                    self.say(format!("stats {}", path.display()));
                }
                Action::Quit => return Ok(false),
            }
        }
        Ok(true)
    }

    /// The state a `stats` action writes.
    pub(super) fn stats_json(&self) -> Value {
        let breps: Vec<_> = self
            .items
            .iter()
            .filter_map(|i| match i {
                Item::Brep(b) => Some(b.report),
                _ => None,
            })
            .collect();
        let (bytes, cells, views, in_flight): (u64, usize, u64, usize) =
            self.tsc.iter().fold((0, 0, 0, 0), |a, t| {
                let r = &t.refinement;
                (
                    a.0 + r.bytes_read,
                    a.1 + r.cells,
                    a.2 + r.views,
                    a.3 + r.in_flight,
                )
            });
        let c = &self.nav.camera;
        self.stats.to_json(json!({
            "triangles": self.triangles(),
            "mode": self.settings.mode.name(),
            "shading": self.settings.shading.name(),
            "edges": self.settings.edges,
            "cracks": self.cracks.name(),
            "subdivision_level": self.shown_level,
            "subdivision_scheme": self.subdiv_scheme,
            "subdivision_device": self.subdiv_device,
            "subdivision_topologies": self.topologies,
            "lod": self.lod,
            "partition": self.show_partition,
            "triangles_near_target": self.triangles_near_target(),
            "sessions": self.tsc.iter().map(|t| {
                t.refinement.sessions.load(std::sync::atomic::Ordering::Relaxed)
            }).sum::<u64>(),
            "frame_index": self.frame_index,
            "frames_total": self.frames.len(),
            "bytes_read": bytes,
            "cells": cells,
            "views": views,
            "refining": in_flight > 0,
            "background_jobs": self.background.busy,
            "adapter": self.renderer.adapter_info(),
            "size": [self.settings.width, self.settings.height],
            "camera": {"eye": c.eye.to_array(), "target": c.target.to_array(),
                       "up": c.up.to_array(), "fov": c.fov},
            "step_times_ms": (!breps.is_empty())
                .then(|| crate::ops::render::step_timings(&breps)),
        }))
    }

    /// Triangles shown whose centroid lies within 10 % of the scene's radius of the camera's
    /// target (what a view-dependent refinement puts where the camera looks).
    pub(super) fn triangles_near_target(&self) -> u64 {
        let target = self.nav.camera.target;
        let r = 0.1 * self.nav.bounds.radius();
        let mut n = 0;
        for item in &self.items {
            let Item::Mesh(m) = item else { continue };
            let Some((scene, _)) = &m.shown else { continue };
            let origin = scene.origin;
            for t in scene.vertices.chunks_exact(3) {
                let c = t.iter().fold(glam::DVec3::ZERO, |a, v| {
                    a + glam::DVec3::from(v.position.map(f64::from))
                }) / 3.0
                    + origin;
                n += u64::from(c.distance(target) <= r);
            }
        }
        n
    }
}
