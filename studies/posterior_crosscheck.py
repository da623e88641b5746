"""The diagnosis posterior against GrainLearning (the established Bayesian calibration tool for
DEM, https://github.com/GrainLearning/grainLearning) on the same surrogates and data.

pydem's posterior (pydem.calibration.fit.posterior): uniform prior on the campaign box,
importance sampling from a Sobol/Gaussian mixture, our own chi^2. GrainLearning's: its SMC
data-assimilation step (scipy multivariate normal likelihood, its own weighting and estimators)
on a Halton sample of the prior. GrainLearning's covariance is diagonal (sigma * W * obs^2) while
ours correlates a net's error over the conditions (fit.py), so both are given the whitened
problem: observations and simulations mapped by L^-1 (C = L L^T, identity covariance), shifted by
one constant so that GrainLearning's relative weights stay finite, and W = 1 / obs^2 normalised by
its geometric mean g, sigma = g: the same likelihood. Same posterior, two independent
implementations: the means and standard deviations must agree within the sampling error.

GrainLearning needs numpy < 2, so it runs in a venv of its own:
    python3 -m venv /tmp/glvenv && /tmp/glvenv/bin/pip install "numpy<2" grainlearning cffi h5py scipy
    /tmp/glvenv/bin/python studies/posterior_crosscheck.py [--sets 6]
Writes studies/results/posterior_crosscheck.json."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def grainlearning_posterior(model, samples: int, seed: int):
    from grainlearning import DynamicSystem
    from grainlearning.inference import SMC
    from grainlearning.sampling import generate_params_qmc
    shift = 10.0 + float(np.abs(model.white(model.y)).max())
    y = model.white(model.y) + shift  # identity covariance in these units
    w = 1.0 / y ** 2
    g = float(np.exp(np.mean(np.log(w))))
    system = DynamicSystem(obs_data=y[:, None], param_min=list(model.lo), param_max=list(model.hi), num_samples=samples,
                           param_names=list(model.free), ctrl_data=np.zeros(1), inv_obs_weight=list(w))
    system.param_data = generate_params_qmc(system, samples, method="halton", seed=seed)
    system.set_sim_data((model.white_rows(model.predict(system.param_data)) + shift)[:, :, None])
    smc = SMC(ess_target=0.3, scale_cov_with_max=False)
    smc.data_assimilation_loop(sigma=g, system=system)
    system.compute_estimated_params(smc.posteriors)
    mean = system.estimated_params[-1]
    sd = system.estimated_params_cv[-1] * mean
    return mean, sd, float(smc.ess[-1])


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--preset", default="tiny")
    ap.add_argument("--sets", type=int, default=6)
    ap.add_argument("--samples", type=int, default=2 ** 16)
    ap.add_argument("--rigs", default="ring_shear,aor,hopper")
    a = ap.parse_args()
    from pydem.calibration import synthetic
    from pydem.calibration.fit import Model, minimise, posterior
    from pydem.calibration.setup import load_setup
    stores = [ROOT / f"data/campaigns/diag_{r}_{a.preset}.h5" for r in a.rigs.split(",")]
    setup = load_setup([s for s in stores if s.exists()])
    rng = np.random.default_rng(3)
    rows = []
    for k in range(a.sets):
        truth = synthetic.draw_truth(rng, setup.ranges, setup.candidates, None)
        obs = synthetic.surrogate_set(setup.nets, setup.candidates, truth, rng, synthetic.programme(setup.nets))
        model = Model(obs, setup.nets, setup.ranges, setup.candidates)
        fit = minimise(model)
        ours = posterior(model, fit, samples=a.samples)
        gl_mean, gl_sd, gl_ess = grainlearning_posterior(model, a.samples, seed=k)
        gl_ess *= a.samples  # GrainLearning reports it as a fraction of the samples
        row = {"set": k, "truth": truth.theta, "ess_pydem": ours["ess"], "ess_grainlearning": gl_ess, "parameters": {}}
        for j, name in enumerate(model.free):
            p = ours["parameters"][name]
            se = p["sd"] * (1.0 / np.sqrt(ours["ess"]) + 1.0 / np.sqrt(gl_ess))  # sampling error of the two means
            row["parameters"][name] = {"pydem_mean": p["mean"], "pydem_sd": p["sd"], "gl_mean": float(gl_mean[j]),
                                       "gl_sd": float(gl_sd[j]), "mean_difference_in_sd": (p["mean"] - gl_mean[j]) / p["sd"],
                                       "sd_ratio": float(gl_sd[j] / p["sd"]), "sampling_se_in_sd": float(se / p["sd"])}
            print(f"set {k} {name:18s} pydem {p['mean']:.4f} ± {p['sd']:.4f}   GrainLearning {gl_mean[j]:.4f} ± "
                  f"{gl_sd[j]:.4f}   (ESS {ours['ess']:.0f} / {gl_ess:.0f})")
        rows.append(row)
    out = ROOT / "studies/results/posterior_crosscheck.json"
    diffs = [abs(p["mean_difference_in_sd"]) for r in rows for p in r["parameters"].values()]
    ratios = [p["sd_ratio"] for r in rows for p in r["parameters"].values()]
    summary = {"sets": len(rows), "max_abs_mean_difference_in_sd": max(diffs), "median_abs_mean_difference_in_sd":
               float(np.median(diffs)), "sd_ratio_range": [min(ratios), max(ratios)]}
    out.write_text(json.dumps({"summary": summary, "sets": rows}, indent=1))
    print(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
