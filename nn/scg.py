"""Scaled conjugate gradient (Møller 1993, Neural Networks 6:525-533) as a torch optimizer.

Full-batch and deterministic: each `step(closure)` is one SCG iteration. The curvature along
the search direction comes from a finite difference of gradients (sigma), a Levenberg–Marquardt
scale (lambda) keeps the step safe where the Hessian is not positive definite, and the
comparison parameter Delta decides whether the step is taken. Defaults follow MATLAB trainscg
(sigma 5e-5, lambda 5e-7). Works in the dtype of the parameters (use float64)."""
from __future__ import annotations

import torch
from torch.nn.utils import parameters_to_vector, vector_to_parameters


class SCG(torch.optim.Optimizer):
    def __init__(self, params, sigma: float = 5e-5, lambd: float = 5e-7):
        if not (sigma > 0 and lambd > 0):
            raise ValueError(f"SCG needs sigma > 0 and lambda > 0, got {sigma}, {lambd}")
        super().__init__(params, dict(sigma=sigma, lambd=lambd))
        self.params = [p for g in self.param_groups for p in g["params"]]
        self.n = sum(p.numel() for p in self.params)
        self.successes = 0  # successful (accepted) steps so far
        self._s = None

    def _eval(self, closure, w: torch.Tensor):
        vector_to_parameters(w, self.params)
        with torch.enable_grad():
            loss = closure()
        grad = torch.cat([(p.grad if p.grad is not None else torch.zeros_like(p)).reshape(-1) for p in self.params])
        return float(loss), grad.detach().clone()

    @property
    def gradient_norm(self) -> float:
        return float(self._s["r"].norm()) if self._s else float("nan")

    @torch.no_grad()
    def step(self, closure):
        """One SCG iteration; the closure zeroes the gradients, computes and back-propagates the loss
        and returns it. Returns the loss at the (possibly new) parameters."""
        g = self.param_groups[0]
        if self._s is None:
            w = parameters_to_vector(self.params).detach().clone()
            e, grad = self._eval(closure, w)
            self._s = dict(w=w, e=e, r=-grad, p=-grad, lam=g["lambd"], lam_bar=0.0, success=True, k=1, delta=0.0)
        s = self._s
        w, r, p = s["w"], s["r"], s["p"]
        p2 = float(p @ p)
        if p2 == 0.0:  # zero gradient: at a stationary point
            vector_to_parameters(w, self.params)
            return s["e"]
        if s["success"]:  # second-order information along p
            sig = g["sigma"] / p2 ** 0.5
            _, grad_plus = self._eval(closure, w + sig * p)
            s["delta"] = float(p @ (grad_plus + r)) / sig  # p . (E'(w + sig p) - E'(w)) / sig
        delta = s["delta"] + (s["lam"] - s["lam_bar"]) * p2
        if delta <= 0:  # make the Hessian approximation positive definite
            s["lam_bar"] = 2.0 * (s["lam"] - delta / p2)
            delta = -delta + s["lam"] * p2
            s["lam"] = s["lam_bar"]
        mu = float(p @ r)
        alpha = mu / delta
        w_new = w + alpha * p
        e_new, grad_new = self._eval(closure, w_new)
        comparison = 2.0 * delta * (s["e"] - e_new) / (mu * mu) if mu != 0 else -1.0
        if comparison >= 0:  # a successful reduction: take the step
            r_new = -grad_new
            s["lam_bar"], s["success"] = 0.0, True
            self.successes += 1
            if s["k"] % self.n == 0:  # restart with steepest descent every N steps
                p_new = r_new
            else:
                beta = (float(r_new @ r_new) - float(r_new @ r)) / mu
                p_new = r_new + beta * p
            s.update(w=w_new, e=e_new, r=r_new, p=p_new)
            s["k"] += 1
            if comparison >= 0.75:
                s["lam"] = 0.25 * s["lam"]
        else:
            s["lam_bar"], s["success"] = s["lam"], False
        if comparison < 0.25:
            s["lam"] = s["lam"] + delta * (1.0 - comparison) / p2
        vector_to_parameters(s["w"], self.params)
        return s["e"]
