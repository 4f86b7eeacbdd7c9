//! The device's loss and recovery: a lost device is replaced, every
//! pipeline rebuilt from its last good module, and the process keeps
//! running.

use super::Daemon;
use super::reload::Succeeded;
use crate::gpu;
use crate::protocol::ServerEvent;
use crate::serve::event::Event;

impl Daemon {
    pub(super) fn install_lost_callback(&self) {
        let tx = self.events.clone();
        let device = self.device_resets;
        self.gpu().device.set_device_lost_callback(move |reason, message| {
            let _ = tx.send(Event::DeviceLost { device, reason, message });
        });
    }

    pub(super) fn device_lost(&mut self, device: u32, reason: wgpu::DeviceLostReason, message: String) {
        if device != self.device_resets {
            return; // about a device already replaced
        }
        let requested = std::mem::take(&mut self.destroy_requested);
        if reason == wgpu::DeviceLostReason::Destroyed && message.is_empty() && !requested {
            return; // destroyed by loupe itself, not lost
        }
        let reason = if requested && message.is_empty() {
            "device destroyed on request (POST /api/debug/lose-device)".to_owned()
        } else {
            format!("{reason:?}: {message}")
        };
        self.recover_device(reason);
    }

    /// A lost device is replaced and every pipeline rebuilt from its last
    /// good module; the process keeps running.
    pub(super) fn recover_device(&mut self, reason: String) {
        log::warn!("device lost: {reason}");
        match gpu::open() {
            Ok(g) => {
                let problems = self.session.replace_device(g);
                self.device_resets += 1;
                if let Some(display) = &self.config.display {
                    display.replace(self.session.gpu());
                }
                // Frames of the old device never come back; the reloads
                // they were to announce go with the next frame instead.
                let lost: Vec<Succeeded> = self.in_flight.drain(..).flat_map(|f| f.reloads).collect();
                self.reloads.device_replaced(lost);
                self.gpu_errors.clear();
                self.gpu_error_files.clear();
                self.install_lost_callback();
                // The snapshots first: a client reading `/api/status` on the
                // event sees the new device.
                self.dirty = true;
                self.publish_state();
                self.shared.publish(ServerEvent::DeviceLost { message: reason, recovered: problems.is_empty() });
            }
            Err(e) => {
                self.shared.publish(ServerEvent::DeviceLost { message: format!("{reason}; reopening failed: {e}"), recovered: false })
            }
        }
    }
}
