//! The results as Markdown (`bench/results/<date>-<device>.md`): one table per suite,
//! every timing as "median (min–max)" over the repetitions, the sizes stated with each
//! table, and a paragraph on where the time goes written from the profile's numbers.

pub use super::number::num;
use super::report::BenchReport;
use super::spread::Spread;
use std::fmt::Write as _;

/// `median (min–max)` of a spread times `k`.
fn spread(s: &Spread, k: f64) -> String {
    if s.min == s.max {
        num(s.median * k)
    } else {
        format!(
            "{} ({}–{})",
            num(s.median * k),
            num(s.min * k),
            num(s.max * k)
        )
    }
}

fn pct(x: f64) -> String {
    if x.is_finite() {
        format!("{:.1} %", 100.0 * x)
    } else {
        "–".into()
    }
}

pub fn render(r: &BenchReport) -> String {
    let mut md = String::new();
    let m = &r.machine;
    let _ = writeln!(md, "# lanterna bench — {}, {}\n", r.date, m.device);
    if r.quick {
        let _ = writeln!(
            md,
            "**Quick mode**: tiny sizes that prove the bench runs; these numbers measure nothing worth reading.\n"
        );
    }
    let _ = writeln!(
        md,
        "Made by `{}` in {:.0} s (load average before / after: {} / {}).\n",
        r.command,
        r.total_seconds,
        r.load_average_start.as_deref().unwrap_or("?"),
        r.load_average_end.as_deref().unwrap_or("?")
    );
    let _ = writeln!(
        md,
        "Machine: {} ({}, driver {}, Vulkan {}), {} CPU cores ({}){}, {}; lanterna {}.\n",
        m.device,
        m.device_type,
        m.driver,
        m.vulkan_api,
        m.cpu_cores,
        m.cpu_model,
        m.lp_num_threads
            .as_ref()
            .map(|t| format!(", LP_NUM_THREADS={t}"))
            .unwrap_or_default(),
        m.os,
        m.lanterna_version
    );
    let _ = writeln!(
        md,
        "Every configuration runs once to warm up ({} spp, not recorded), then {} time(s) with seed {} and the same sample indices; \
         timings are **median (min–max)** over those runs. Max depth {} (path segments, as Mitsuba's), uniform source distribution, \
         RIS M = 32, guiding with 30 % of the spp budget training. GPU time is from timestamp queries around each dispatch.\n",
        r.sizes.warmup_spp, r.repeat, r.seed, r.sizes.max_depth
    );
    if let Some(t) = &r.traversal {
        traversal(&mut md, t);
    }
    if let Some(t) = &r.throughput {
        throughput(&mut md, t);
    }
    if let Some(s) = &r.scaling {
        scaling(&mut md, s);
    }
    if let Some(g) = &r.guiding {
        guiding(&mut md, g);
    }
    if let Some(q) = &r.quality {
        quality(&mut md, q);
    }
    mitsuba(&mut md, r);
    if let Some(p) = &r.profile {
        profile(&mut md, p, r);
    }
    if let Some(t) = &r.trend {
        trend(&mut md, t);
    }
    md
}

fn traversal(md: &mut String, t: &super::traversal::TraversalBench) {
    let _ = writeln!(md, "## Traversal\n");
    let _ = writeln!(
        md,
        "The same rays through the device's ray queries and through the software traversal (`inc/bvh.glsl`), \
         M rays per GPU second; camera rays of an image twice the throughput size, one cosine bounce ray and one shadow ray \
         (to a point on a random emissive triangle) per camera hit.\n"
    );
    let _ = writeln!(
        md,
        "| scene | BVH (nodes, leaf ≤, depth) | rays | count | ray query M rays/s | software M rays/s | speed-up | hits differing |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    for s in &t.scenes {
        for x in &s.sets {
            let rq = x.ray_query_mrays_per_s.as_ref();
            let _ = writeln!(
                md,
                "| {} | {}, {}, {} | {} | {} | {} | {} | {} | {} |",
                s.scene,
                s.bvh_nodes,
                s.bvh_max_leaf,
                s.bvh_depth,
                x.set,
                x.rays,
                rq.map(|r| spread(r, 1.0)).unwrap_or_else(|| "—".into()),
                spread(&x.software_mrays_per_s, 1.0),
                rq.map(|r| format!("{:.1}×", x.software_mrays_per_s.median / r.median))
                    .unwrap_or_else(|| "—".into()),
                x.different_hits
                    .map(|d| d.to_string())
                    .unwrap_or_else(|| "—".into()),
            );
        }
    }
    let _ = writeln!(md);
}

fn throughput(md: &mut String, t: &super::throughput::Throughput) {
    let _ = writeln!(md, "## Throughput\n");
    for s in &t.scenes {
        let spp = s.methods.first().map(|m| m.spp).unwrap_or(0);
        let _ = writeln!(
            md,
            "`{}` at {}×{}, {} traversal, {} spp per run ({} triangles, {} emissive in {} light models):\n",
            s.scene, s.width, s.height, s.traversal, spp, s.triangles, s.emissive_triangles, s.light_models
        );
        let _ = writeln!(
            md,
            "| method | M samples/s (wall) | M samples/s (GPU) | M rays/s: camera | bounce | shadow | rays/sample (c/b/s) | GPU s | wall s | GPU/wall |"
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|");
        for x in &s.methods {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {:.2} / {:.2} / {:.2} | {} | {} | {} |",
                x.method,
                spread(&x.samples_per_s, 1e-6),
                spread(&x.samples_per_gpu_s, 1e-6),
                spread(&x.camera_rays_per_s, 1e-6),
                spread(&x.bounce_rays_per_s, 1e-6),
                spread(&x.shadow_rays_per_s, 1e-6),
                x.camera_rays_per_sample,
                x.bounce_rays_per_sample,
                x.shadow_rays_per_sample,
                spread(&x.gpu_seconds, 1.0),
                spread(&x.wall_seconds, 1.0),
                pct(x.gpu_share.median),
            );
        }
        let _ = writeln!(md);
    }
    let _ = writeln!(
        md,
        "Samples are camera paths; guided methods count their training passes too (their wall time includes training, read-back, refit and upload).\n"
    );
}

fn scaling(md: &mut String, s: &super::scaling::Scaling) {
    let _ = writeln!(md, "## Light-count scaling\n");
    let _ = writeln!(
        md,
        "The street scene generated with more lamps, {}×{}, {} spp per run; **GPU milliseconds per spp** \
         (guided methods: their render phase only, the tree frozen; RIS with M = {}):\n",
        s.width, s.height, s.spp, s.ris_candidates
    );
    let methods: Vec<String> = s
        .points
        .first()
        .map(|p| p.methods.iter().map(|m| m.method.clone()).collect())
        .unwrap_or_default();
    let _ = writeln!(
        md,
        "| emissive triangles | lamps | triangles | {} |",
        methods.join(" | ")
    );
    let _ = writeln!(md, "|---|---|---|{}", "---|".repeat(methods.len()));
    for p in &s.points {
        let cells: Vec<String> = p
            .methods
            .iter()
            .map(|m| spread(&m.gpu_seconds_per_spp, 1e3))
            .collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} |",
            p.emissive_triangles,
            p.lamps,
            p.triangles,
            cells.join(" | ")
        );
    }
    if !s.growth.is_empty() {
        let cells: Vec<String> = s
            .growth
            .iter()
            .map(|g| format!("**×{:.2}** (wall ×{:.2})", g.gpu, g.wall))
            .collect();
        let _ = writeln!(md, "| growth, first → last | | | {} |", cells.join(" | "));
        let cells: Vec<String> = s
            .growth
            .iter()
            .map(|g| format!("×{:.2}", g.gpu_over_control))
            .collect();
        let _ = writeln!(md, "| growth ÷ the control's | | | {} |", cells.join(" | "));
    }
    let _ = writeln!(
        md,
        "\nThe goal is a cost per sample that does not grow with the light count (growth ×1). \
         The scene's triangle count grows with the lamps too (every lamp is a mesh instance), so part of any growth is traversal \
         of a larger scene: the `pt-d1` column (max depth 1: camera rays and first hits, no light sampling) is that control.\n"
    );
}

fn guiding(md: &mut String, g: &super::guiding::GuidingOverhead) {
    let _ = writeln!(md, "## Guiding overhead\n");
    let _ = writeln!(
        md,
        "`{}` at {}×{}. Per training iteration: the training pass (wall and GPU), reading the training quadtrees back, \
         the CPU refit, and flattening + uploading the tree; then the tree's size after the refit.\n",
        g.scene, g.width, g.height
    );
    for m in &g.methods {
        let _ = writeln!(
            md,
            "`{}`, {} spp ({} training): training {} s; refit + upload = **{}** of the training time \
             (goal ≤ {}: {}); read-back {}.\n",
            m.method,
            m.spp,
            m.training_spp,
            spread(&m.training_seconds, 1.0),
            pct(m.refit_upload_share.median),
            pct(g.goal_share),
            if m.goal_met { "met" } else { "**not met**" },
            pct(m.readback_share.median)
        );
        let _ = writeln!(
            md,
            "| iteration | spp | pass ms | GPU ms | read-back ms | refit ms | upload ms | leaves | sampling / training nodes | KiB |"
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|");
        for i in &m.iterations {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} / {} | {:.1} |",
                i.iteration,
                i.spp,
                spread(&i.pass_seconds, 1e3),
                spread(&i.gpu_seconds, 1e3),
                spread(&i.readback_seconds, 1e3),
                spread(&i.refit_seconds, 1e3),
                spread(&i.upload_seconds, 1e3),
                i.leaves,
                i.sampling_nodes,
                i.training_nodes,
                i.gpu_bytes as f64 / 1024.0
            );
        }
        let _ = writeln!(md);
    }
}

fn quality(md: &mut String, q: &super::quality::Quality) {
    let _ = writeln!(md, "## Quality at equal spp and equal time\n");
    for s in &q.scenes {
        let _ = writeln!(
            md,
            "`{}` at {}×{}: MAE against a `pt` reference of {} spp (its own MAE ≈ {}, from its two halves), \
             seeds {:?}; **MAE ratio to `pt`** at the same budget (below 1 is better). Equal time includes guided training.\n",
            s.scene,
            s.width,
            s.height,
            s.reference_spp,
            num(s.reference_mae),
            s.seeds
        );
        let _ = writeln!(md, "| method | budget | spp reached | MAE | ratio to pt |");
        let _ = writeln!(md, "|---|---|---|---|---|");
        for r in &s.records {
            let budget = if r.budget_kind == "spp" {
                format!("{} spp", r.budget)
            } else {
                format!("{} s", r.budget)
            };
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | **{}** |",
                r.method,
                budget,
                spread(&r.spp, 1.0),
                spread(&r.mae, 1.0),
                spread(&r.mae_ratio_to_pt, 1.0)
            );
        }
        let _ = writeln!(md);
    }
}

fn mitsuba(md: &mut String, r: &BenchReport) {
    if r.mitsuba.is_none() && r.mitsuba_skipped.is_none() {
        return;
    }
    let _ = writeln!(md, "## Peer comparison with Mitsuba 3\n");
    if let Some(why) = &r.mitsuba_skipped {
        let _ = writeln!(md, "Skipped: {why}.\n");
    }
    let Some(p) = &r.mitsuba else {
        return;
    };
    let _ = writeln!(
        md,
        "Scenes exported with `lanterna scene export-mitsuba`, rendered by Mitsuba's `path` integrator at the same max depth and size \
         (`{}`). Agreement: lanterna `pt` batches vs Mitsuba runs, Welch tests of the image mean, of 8×8 blocks and of pixels \
         (family-wise α = 10⁻³); it applies only where the export is exact. Equal time: every lanterna method and Mitsuba's `path` \
         get the time of one lanterna `pt` batch (Mitsuba's spp is rescaled by the time it took until within 5 %, and the closest of up to six tries counts; the seconds each render took are shown; a ratio where either side missed the budget by more than 10 % is marked \"not equal time\"); MAE against a Mitsuba reference.\n",
        p.script
    );
    let _ = writeln!(
        md,
        "| scene | size | exact | mean lanterna/Mitsuba − 1 (R, G, B) | blocks / pixels agree | lanterna `pt` M samples/s | Mitsuba `path` M samples/s | speed ratio | equal time | Mitsuba MAE (spp, s) | best lanterna: MAE (spp, s) | MAE ratio |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|---|");
    for s in &p.scenes {
        let diff: Vec<String> = s
            .mean_rel_diff
            .iter()
            .zip(&s.mean_rel_diff_stderr)
            .map(|(d, e)| format!("{:+.2} % ± {:.2}", 100.0 * d, 100.0 * e))
            .collect();
        let best = s
            .lanterna_equal_time
            .iter()
            .find(|m| m.method == s.best_method);
        let _ = writeln!(
            md,
            "| {} | {}×{} | {} | {} | {} / {} | {} | {} | {} | {:.2} s | {} ({}, {:.2} s) | `{}`: {} ({}, {:.2} s) | **{:.2}**{} |",
            s.scene,
            s.width,
            s.height,
            if s.exact { "yes" } else { "no" },
            diff.join(", "),
            if s.blocks_agree { "yes" } else { "**no**" },
            if s.pixels_agree { "yes" } else { "**no**" },
            spread(&s.lanterna_samples_per_s, 1e-6),
            num(s.mitsuba_samples_per_s * 1e-6),
            num(s.speed_ratio),
            s.equal_time_seconds,
            num(s.mitsuba_equal_time_mae),
            s.mitsuba_equal_time_spp,
            s.mitsuba_equal_time_seconds,
            s.best_method,
            best.map(|b| spread(&b.mae, 1.0)).unwrap_or_default(),
            best.map(|b| num(b.spp.median)).unwrap_or_default(),
            best.map_or(0.0, |b| b.seconds.median),
            s.best_mae_ratio_to_mitsuba,
            unequal_time_note(
                s.equal_time_seconds,
                s.mitsuba_equal_time_seconds,
                best.map_or(s.equal_time_seconds, |b| b.seconds.median)
            )
        );
    }
    let _ = writeln!(md);
    for s in &p.scenes {
        let cells: Vec<String> = s
            .lanterna_equal_time
            .iter()
            .map(|m| {
                format!(
                    "`{}` {} ({} spp)",
                    m.method,
                    num(m.mae.median),
                    num(m.spp.median)
                )
            })
            .collect();
        let _ = writeln!(
            md,
            "- `{}` at equal time, lanterna MAE: {}.",
            s.scene,
            cells.join(", ")
        );
        if !s.exact {
            let _ = writeln!(
                md,
                "  Not exact ({} approximation(s), e.g. {}): agreement is not expected; speed and MAE still compare like for like.",
                s.approximations.len(),
                s.approximations.first().map(String::as_str).unwrap_or("")
            );
        }
    }
    let _ = writeln!(
        md,
        "\nInstall: `pip install mitsuba` (3.x); the comparison uses the `llvm_ad_rgb` variant when Dr.Jit finds LLVM ≥ 16 \
         (`DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1` with Debian's libllvm19; the bench sets it when that \
         file exists) and falls back to `scalar_rgb` otherwise. See `bench/README.md`.\n"
    );
}

/// How far a render's time may miss the equal-time budget before the comparison is
/// marked as not at equal time.
const EQUAL_TIME_TOLERANCE: f64 = 0.10;

/// A note for a peer row whose Mitsuba render or best lanterna method took more than
/// `EQUAL_TIME_TOLERANCE` away from the budget (empty when both are within it). At
/// budgets of a tenth of a second neither side always lands on it: lanterna renders
/// whole passes, and one Mitsuba call's time can jump between tries.
fn unequal_time_note(budget: f64, mitsuba: f64, lanterna: f64) -> String {
    let off = |s: f64| !(budget > 0.0 && (s / budget - 1.0).abs() <= EQUAL_TIME_TOLERANCE);
    if off(mitsuba) || off(lanterna) {
        format!(" (not equal time: Mitsuba {mitsuba:.2} s, lanterna {lanterna:.2} s, budget {budget:.2} s)")
    } else {
        String::new()
    }
}

fn profile(md: &mut String, p: &super::profile::Profile, r: &BenchReport) {
    let _ = writeln!(md, "## Where the time goes\n");
    let _ = writeln!(
        md,
        "`{}` at {}×{}; GPU nanoseconds per camera path under settings that switch the kernel's parts on one at a time \
         (`ao-d2`: depth 2 with direction sampling only, no light sampling):\n",
        p.scene, p.width, p.height
    );
    let _ = writeln!(
        md,
        "| configuration | phase | spp | GPU ns/sample | wall ns/sample | rays/sample (c/b/s) |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for e in &p.entries {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {:.2} / {:.2} / {:.2} |",
            e.name,
            e.phase,
            e.spp,
            spread(&e.gpu_ns_per_sample, 1.0),
            spread(&e.wall_ns_per_sample, 1.0),
            e.camera_rays_per_sample,
            e.bounce_rays_per_sample,
            e.shadow_rays_per_sample
        );
    }
    let _ = writeln!(md);
    if !p.parts.is_empty() {
        let _ = writeln!(
            md,
            "Parts, from differences between those configurations (each configuration's fastest run, the least disturbed by other work):\n"
        );
        let _ = writeln!(md, "| of | part | GPU ns/sample | share |");
        let _ = writeln!(md, "|---|---|---|---|");
        for x in &p.parts {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} |",
                x.of,
                x.part,
                num(x.ns_per_sample),
                pct(x.share)
            );
        }
        let _ = writeln!(md);
    }
    if !p.lanes.is_empty() {
        let _ = writeln!(
            md,
            "SIMD lanes doing work (lane-statistics kernel, depth {}): in the software traversal loop, all rays, and in the \
             path loop, where a lane whose path ended waits for its subgroup's longest:\n",
            r.sizes.max_depth
        );
        let _ = writeln!(
            md,
            "| method | traversal loop | path loop | traversal steps per ray |"
        );
        let _ = writeln!(md, "|---|---|---|---|");
        let share = |u: Option<f64>| u.map_or("–".to_string(), pct);
        for l in &p.lanes {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} |",
                l.method,
                share(l.traversal),
                share(l.path),
                l.steps_per_ray
                    .map_or("–".to_string(), |s| format!("{s:.1}"))
            );
        }
        let _ = writeln!(md);
    }
    let _ = writeln!(md, "{}\n", summary(p, r));
}

/// The "where the time goes" paragraph, from the numbers.
fn summary(p: &super::profile::Profile, r: &BenchReport) -> String {
    let mut text = String::new();
    let find = |name: &str| p.entries.iter().find(|e| e.name == name);
    let depth = r.sizes.max_depth;
    if let Some(pt) = find(&format!("pt-d{depth}")) {
        let rays =
            pt.camera_rays_per_sample + pt.bounce_rays_per_sample + pt.shadow_rays_per_sample;
        let _ = write!(
            text,
            "On {}, a `pt` path of depth {depth} costs {} µs of GPU time for {:.2} rays, about {} µs per ray all included. ",
            r.machine.device,
            num(pt.gpu_ns_per_sample.median / 1e3),
            rays,
            num(pt.gpu_ns_per_sample.median / 1e3 / rays.max(1e-9))
        );
        if let Some(d1) = find("pt-d1") {
            let _ = write!(
                text,
                "The camera ray with its first hit alone is {} of it. ",
                pct(d1.gpu_ns_per_sample.median / pt.gpu_ns_per_sample.median)
            );
        }
        let gpu_share = pt.gpu_ns_per_sample.median / pt.wall_ns_per_sample.median;
        let _ = write!(
            text,
            "GPU time is {} of wall time (the rest is submission and waiting; reading the film back takes {} ms). ",
            pct(gpu_share),
            num(p.film_readback_ms.median)
        );
    }
    for part in &p.parts {
        if part.part.starts_with("RIS candidates") {
            let _ = write!(
                text,
                "In {}, evaluating the candidates (light sample, BSDF and p̂, source pdfs) takes {} of the time \
                 ({} ns per sample). ",
                part.of,
                pct(part.share),
                num(part.ns_per_sample)
            );
        }
        if part.part.starts_with("shadow rays beyond") {
            let _ = write!(
                text,
                "The extra shadow rays that RIS leads to (it finds a light worth testing more often) take {}. ",
                pct(part.share)
            );
        }
        if part.part.starts_with("RIS candidates and") {
            let _ = write!(
                text,
                "In {}, the candidates and the extra shadow rays they lead to take {} of the time. ",
                part.of,
                pct(part.share)
            );
        }
        if part.part.starts_with("guiding") {
            let _ = write!(
                text,
                "Guiding (tree lookups, sampling and pdfs) is {} of the cost per ray of the {}. ",
                pct(part.share),
                part.of
            );
        }
        if part.part.starts_with("recording") {
            let _ = write!(
                text,
                "Recording the training data is {} of the {}. ",
                pct(part.share),
                part.of
            );
        }
    }
    text.trim_end().to_string()
}

fn trend(md: &mut String, t: &super::trend::Trend) {
    let _ = writeln!(md, "## Guiding against training paths\n");
    let _ = writeln!(
        md,
        "MAE ratios at equal total spp (guided methods train on 30 % of it), against a `pt` reference per image size; \
         in parentheses with the reference's own MAE removed in quadrature. Seeds {:?}; training paths = pixels × training spp. \
         The paper (Bistro, 1024², 1000 spp): guided/pt 0.69, guided-ris/pt 0.41.\n",
        t.seeds
    );
    let _ = write!(md, "| scene | size | spp | training paths | ref. MAE |");
    for (name, _, _) in super::trend::RATIOS {
        let _ = write!(md, " {name} |");
    }
    let _ = writeln!(md, "\n|---|---|---|---|---|---|---|---|---|");
    for p in &t.points {
        let _ = write!(
            md,
            "| {} | {}×{} | {} | {:.1e} | {} |",
            p.scene,
            p.width,
            p.height,
            p.spp,
            p.training_paths as f64,
            num(p.reference_mae)
        );
        for r in &p.ratios {
            let _ = write!(md, " {} ({}) |", num(r.raw.median), num(r.corrected.median));
        }
        let _ = writeln!(md);
    }
    if !t.skipped.is_empty() {
        let _ = writeln!(md, "\nNot run:\n");
        for s in &t.skipped {
            let _ = writeln!(md, "- {s}");
        }
    }
    let _ = writeln!(md);
}

#[cfg(test)]
mod tests {
    use super::unequal_time_note;

    #[test]
    fn peer_rows_off_the_budget_are_marked() {
        // Within 10 % on both sides: a plain ratio.
        assert_eq!(unequal_time_note(6.49, 6.50, 6.50), "");
        assert_eq!(unequal_time_note(1.0, 0.91, 1.09), "");
        // The short row of 2026-11-26: Mitsuba's last try took 0.05 s of 0.13 s.
        assert!(unequal_time_note(0.134, 0.0496, 0.134).contains("not equal time"));
        // lanterna's whole passes overshoot a tiny budget.
        assert!(unequal_time_note(0.134, 0.134, 0.162).contains("not equal time"));
        // No budget, or one that is not a number, never reads as equal time.
        assert!(!unequal_time_note(0.0, 0.0, 0.0).is_empty());
        assert!(!unequal_time_note(f64::NAN, 1.0, 1.0).is_empty());
    }
}
