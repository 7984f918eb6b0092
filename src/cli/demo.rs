// `softrod` without a subcommand: the built-in scene's solve and estimation demo.

use super::*;

fn median_warm_step(
    est: &mut dyn softrod::estimate::Estimator,
    observations: &[Observation],
) -> Result<f64> {
    let mut times = Vec::with_capacity(observations.len());
    for o in observations {
        let t = std::time::Instant::now();
        est.step(o)?.converged()?;
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    Ok(times.get(times.len() / 2).copied().unwrap_or(f64::NAN))
}

pub(super) fn default_run() -> Result<()> {
    solve_summary()?;
    outln!();
    estimation_demo()
}

/// The main job: an unknown payload on the two-section robot, five noisy
/// markers, both backends.
fn estimation_demo() -> Result<()> {
    let scene = Scene::two_section();
    let robot = scene.robot()?;
    let known = scene.loads()?;
    let tip_mass_kg = 0.02;
    let uniform = [0.0, -0.5];
    let mut truth = known.clone();
    truth.point_forces.push(PointForce {
        s_m: robot.length(),
        force_n: vec![0.0, -9.81 * tip_mass_kg],
    });
    truth.line_loads.push(LineLoad::Uniform {
        w_n_per_m: uniform.to_vec(),
    });
    let eq = StaticSolver::default().solve(&robot, &truth, None)?;
    let nodes: Vec<usize> = scene.markers.iter().filter_map(|m| m.node).collect();
    let sigma = 1e-5;
    let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &nodes)?.with_noise(sigma, 1);
    let true_force = [
        uniform[0] * robot.length(),
        uniform[1] * robot.length() - 9.81 * tip_mass_kg,
    ];
    let tip = |q: &[f64]| (q[q.len() - 4], q[q.len() - 3]);
    let (tx, ty) = tip(eq.q.as_slice());
    outln!(
        "Estimation (Sec. III): unknown payload = {:.0} g tip mass + uniform {:.2} N/m, not known to the estimator",
        tip_mass_kg * 1e3,
        uniform[1]
    );
    outln!(
        "  {} markers at nodes {:?}, seeded noise {:.2} mm; alpha by the discrepancy principle",
        nodes.len(),
        nodes,
        sigma * 1e3
    );
    outln!(
        "  truth:    tip ({:+.5}, {:+.5}) m, resultant ({:+.4}, {:+.4}) N",
        tx,
        ty,
        true_force[0],
        true_force[1]
    );
    for backend in [Backend::Newton, Backend::Sqp] {
        let settings = softrod::estimate::EstimatorSettings {
            backend,
            ..scene.solver.estimator.clone()
        };
        let mut est = settings.build_for(&robot, &known)?;
        let e = est.step(&obs)?.converged()?;
        let (ex, ey) = tip(e.q.as_slice());
        let sd: Vec<f64> = (0..2)
            .map(|a| e.resultant_force_cov()[(a, a)].max(0.0).sqrt())
            .collect();
        outln!(
            "  {:<6}    tip ({:+.5}, {:+.5}) m (error {:.3} mm), resultant ({:+.4} ± {:.4}, {:+.4} ± {:.4}) N, moment {:+.4} N·m; {} iterations, alpha {:.3e}, first step {:.1} ms",
            backend.name(),
            ex,
            ey,
            (ex - tx).hypot(ey - ty) * 1e3,
            e.resultant_force_n[0],
            sd[0],
            e.resultant_force_n[1],
            sd[1],
            e.resultant_moment_nm[0],
            e.report.iterations,
            e.report.alpha,
            e.report.wall_time_s * 1e3
        );
        // streaming: 50 new noisy frames of the same scene, warm-started
        let frames: Vec<Observation> = (0..50)
            .map(|k| {
                Ok(Observation::of_nodes(&robot, eq.q.as_slice(), &nodes)?
                    .with_noise(sigma, 100 + k))
            })
            .collect::<softrod::Result<_>>()?;
        let t = median_warm_step(est.as_mut(), &frames)?;
        outln!(
            "            warm step (new noisy frame, median of 50): {:.1} µs",
            t * 1e6
        );
    }
    outln!(
        "Run `softrod estimate examples/two_section.json --backend newton --out estimate.json` for a full result."
    );
    Ok(())
}

fn solve_summary() -> Result<()> {
    let scene = Scene::two_section();
    let robot = scene.robot()?;
    let out = solve(&scene, None)?;
    let spec = robot.spec();
    outln!(
        "softrod {} — built-in scene `{}`",
        env!("CARGO_PKG_VERSION"),
        scene.name
    );
    outln!("  {}", scene.description);
    outln!(
        "  {} sections, {} elements, {:.3} m, weight {:.3} N, pressures {:?} kPa",
        spec.sections.len(),
        robot.n_elements(),
        robot.length(),
        spec.sections
            .iter()
            .map(|s| s.mass_per_length_kg_per_m * s.length_m * 9.81)
            .sum::<f64>(),
        out.pressures_pa.iter().map(|p| p / 1e3).collect::<Vec<_>>()
    );
    outln!("  equilibrium: {}", out.report);
    outln!("  solve time: {:.1} µs", out.report.wall_time_s * 1e6);
    outln!(
        "  tip position: ({:+.4}, {:+.4}) m, tip angle {:+.2}°",
        out.tip_position_m[0],
        out.tip_position_m[1],
        out.tip_angle_rad.unwrap_or(f64::NAN).to_degrees()
    );
    outln!("  markers:");
    for m in &scene.markers {
        if let Some(n) = m.node {
            let p = &out.nodes[n].position_m;
            outln!(
                "    node {:2} (s = {:.3} m): ({:+.4}, {:+.4}) m",
                n,
                out.nodes[n].s_m,
                p[0],
                p[1]
            );
        }
    }
    outln!("Run `softrod solve examples/two_section.json --out result.json` for the full result.");
    Ok(())
}
