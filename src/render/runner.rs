//! The GPU renderer behind `eval::compare`: one scene on the device, the method switched
//! per run, every other setting as given. The command line's `compare` and the Python
//! module's `compare()` both run their comparisons through it. Each image's metadata
//! records the settings of its own run (its method and that method's settings).

use super::output::{outcome_image, set_settings_meta};
use super::{run, Method, RenderSettings, Renderer};
use crate::eval::compare::{Budget, MethodResult, MethodRunner};
use crate::eval::BoxError;
use crate::image_io::RenderMeta;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

pub struct CompareRunner<'a> {
    pub renderer: &'a mut Renderer,
    /// Settings of every run but the method.
    pub base: RenderSettings,
    /// Scene load and device setup, reported with every result.
    pub setup_seconds: f64,
    /// Metadata of every image (the method and the render time are filled in per run).
    pub meta: RenderMeta,
    /// Set to stop: the run in progress ends at its next chunk and fails as interrupted.
    pub cancel: &'a AtomicBool,
    /// Called with the spp done between chunks (a place to notice interruptions).
    pub progress: &'a mut dyn FnMut(u64),
}

impl MethodRunner for CompareRunner<'_> {
    fn prepare(&mut self, methods: &[String]) -> Result<(), BoxError> {
        let methods: Vec<Method> = methods
            .iter()
            .map(|m| m.parse())
            .collect::<Result<_, _>>()?;
        let prep = Instant::now();
        self.renderer.set_settings(self.base.clone())?;
        self.renderer.prepare_methods(&methods)?;
        log::debug!(
            "pipelines of {} methods created in {:.1} s",
            methods.len(),
            prep.elapsed().as_secs_f64()
        );
        Ok(())
    }

    fn render(&mut self, method: &str, budget: Budget) -> Result<MethodResult, BoxError> {
        let method: Method = method.parse()?;
        let settings = RenderSettings {
            method,
            ..self.base.clone()
        };
        let (w, h) = (settings.width, settings.height);
        self.renderer.set_settings(settings.clone())?;
        let prep = Instant::now();
        self.renderer.prepare()?;
        log::debug!(
            "{method}: pipelines ready in {:.1} s",
            prep.elapsed().as_secs_f64()
        );
        let budget = match budget {
            Budget::Spp(n) => run::Budget::Spp(n),
            Budget::Seconds(s) => run::Budget::Seconds(s),
        };
        let out = run::run_method(self.renderer, budget, 0, self.cancel, self.progress)?;
        if self.cancel.load(Ordering::SeqCst) {
            return Err("interrupted".into());
        }
        // `meta` was made from `base`: its settings keys give way to this run's.
        let mut meta = self.meta.clone();
        set_settings_meta(&mut meta, &settings, Some(&self.base));
        meta.render_seconds = Some(out.seconds);
        let image = outcome_image(&out, w, h, meta)?;
        log::info!(
            "{method} {budget:?}: {} spp in {:.2} s",
            out.film.spp,
            out.seconds
        );
        Ok(MethodResult {
            spp: out.stats.samples,
            render_seconds: out.seconds,
            setup_seconds: self.setup_seconds,
            gpu_seconds: Some(out.stats.gpu_seconds),
            training_seconds: method.uses_guiding().then_some(out.training_seconds),
            image,
        })
    }
}
