"""Lognormal fragility from an incremental dynamic analysis (IDA).

P(limit reached | IM = x) = Phi(ln(x / theta) / beta): median theta, dispersion beta.

Fitted by maximum likelihood on each record's limit intensity IM_i (the lowest level at which the
record was seen to reach the limit state), records that never reached it being right-censored at
their highest level run IM_c (all that is known is IM_i > IM_c):

    ln L(theta, beta) = sum_reached ln[phi(z_i) / (beta IM_i)] + sum_censored ln[1 - Phi(z_c)],
    z = ln(IM / theta) / beta.

Without censored records the maximum is the closed form ln theta = mean(ln IM_i),
beta = std(ln IM_i) with divisor n; Baker (2015), "Efficient analytical fragility function fitting
using dynamic structural analysis", Earthquake Spectra 31(1), Eq. 3 (the IDA case), uses the same
mean and the divisor n - 1: both are reported (``baker2015``: over the reached records only).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize
from scipy.stats import norm

METHOD = ("maximum likelihood, lognormal, on each record's limit intensity (the lowest level at which it "
          "reached the limit state); records that never reached it are right-censored at their highest level")


def _neg_log_likelihood(x, ln_im: np.ndarray, ln_cens: np.ndarray) -> float:
    mu, beta = x[0], math.exp(x[1])
    z = (ln_im - mu) / beta
    zc = (ln_cens - mu) / beta
    return -(float(np.sum(norm.logpdf(z) - math.log(beta) - ln_im)) + float(np.sum(norm.logsf(zc))))


def fit_lognormal(limit_im, censored_im=()) -> dict:
    """The fit (see the module docstring): {"median", "dispersion", "method", "n_reached", "n_censored",
    "log_likelihood", "baker2015": {"median", "dispersion"}} with median/dispersion None (and a
    "note") where the data cannot determine them: fewer than two reached records, or the reached
    records all at one level with no censored record above it (with one above, the fit is the
    likelihood's maximum, which is then finite)."""
    ln_im = np.log(np.asarray(limit_im, dtype=float))
    ln_c = np.log(np.asarray(censored_im, dtype=float))
    if np.any(~np.isfinite(ln_im)) or np.any(~np.isfinite(ln_c)):
        raise ValueError("fit_lognormal: intensities must be finite and > 0")
    out = {"method": METHOD, "n_reached": int(ln_im.size), "n_censored": int(ln_c.size), "median": None,
           "dispersion": None, "log_likelihood": None, "baker2015": {"median": None, "dispersion": None}}
    if ln_im.size >= 2:
        out["baker2015"] = {"median": float(np.exp(np.mean(ln_im))), "dispersion": float(np.std(ln_im, ddof=1))}
    if ln_im.size < 2:
        out["note"] = (f"{'no record' if ln_im.size == 0 else 'one record'} reached the limit (fewer than two): "
                       "median and dispersion undetermined")
        return out
    mu0, s0 = float(np.mean(ln_im)), float(np.std(ln_im))
    if s0 == 0.0 and not np.any(ln_c > mu0):
        # every reached record at one level, and no record known to survive above it: the likelihood
        # grows without bound as the dispersion goes to 0
        out["note"] = (f"the {ln_im.size} records that reached the limit all reached it at the same level "
                       f"(IM = {math.exp(mu0):.4g} m/s^2) and no record is known to survive above it: "
                       "median and dispersion undetermined")
        return out
    s0 = s0 or 0.3  # a start for the censored records to resolve (their levels lie above the common level)
    if ln_c.size == 0:  # the closed form of the maximum
        mu, beta = mu0, s0
    else:
        res = minimize(_neg_log_likelihood, [mu0, math.log(s0)], args=(ln_im, ln_c), method="Nelder-Mead",
                       options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 4000})
        mu, beta = float(res.x[0]), math.exp(float(res.x[1]))
    out.update(median=math.exp(mu), dispersion=beta,
               log_likelihood=-_neg_log_likelihood([mu, math.log(beta)], ln_im, ln_c))
    return out


def fragility_curve(median: float, dispersion: float, im) -> np.ndarray:
    """P(limit reached | IM) of the fitted lognormal."""
    return norm.cdf(np.log(np.asarray(im, dtype=float) / median) / dispersion)
