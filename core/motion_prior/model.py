"""The pose prior: how likely a body pose is, learnt from motion capture; numpy alone at run time.

The model (chosen on held-out CMU subjects, ``docs/motion_prior.md``):

* *pose*: a mixture of full-covariance Gaussians over the pose features of :mod:`.features` (the
  limb bones' unit directions in the body's own frame; the bones are listed in the file);
* *change over time*: a zero-mean Gaussian, one variance per feature, on the features' rate of
  change (per second, so it holds at any frame rate).

:meth:`PosePrior.log_likelihood` scores poses; :meth:`PosePrior.flip_gains` scores, for every bone of
every frame, the pose with that bone's depth sign flipped (its vector's depth coordinate negated in
the camera's axes: Taylor's two choices for a bone, with everything below it carried along) against
the pose as it is.  The estimators add ``-log_likelihood`` (times a weight) to their costs wherever
they guess a depth sign.
"""

from __future__ import annotations

import json
import os

import numpy as np

from .features import LIMB_BONES, bone_vectors, features_from_bones

#: Rows per block when scoring many poses at once (bounds memory: block x components x 48 floats).
BLOCK = 2048
FORMAT = "monoskel-pose-prior"
VERSION = 1


def component_log_densities(x: np.ndarray, weights: np.ndarray, means: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """(N, K) log of each weighted Gaussian component's density at the rows of ``x`` (N, D)."""
    chol = np.linalg.cholesky(cov)
    out = np.empty((x.shape[0], len(weights)))
    for j in range(len(weights)):
        y = np.linalg.solve(chol[j], (x - means[j]).T)
        out[:, j] = (np.log(weights[j]) - 0.5 * x.shape[1] * np.log(2 * np.pi)
                     - np.sum(np.log(np.diag(chol[j]))) - 0.5 * np.sum(y * y, axis=0))
    return out


class PosePrior:
    """A Gaussian mixture over pose features plus a Gaussian on their rate of change."""

    def __init__(self, weights: np.ndarray, means: np.ndarray, covariances: np.ndarray,
                 rate_sigma: np.ndarray, meta: dict | None = None):
        self.weights = np.asarray(weights, dtype=float)
        self.means = np.asarray(means, dtype=float)
        self.covariances = np.asarray(covariances, dtype=float)
        self.rate_sigma = np.asarray(rate_sigma, dtype=float)
        self.meta = dict(meta or {})
        self.bones = tuple(int(b) for b in self.meta.get("bones", LIMB_BONES))
        k, d = self.means.shape
        if d != 3 * len(self.bones) or self.covariances.shape != (k, d, d) or self.weights.shape != (k,):
            raise ValueError(f"pose prior arrays do not fit: means {self.means.shape}, covariances "
                             f"{self.covariances.shape}, weights {self.weights.shape}")
        chol = np.linalg.cholesky(self.covariances)                       # C = L L^T
        eye = np.broadcast_to(np.eye(d), (k, d, d))
        whiten = np.swapaxes(np.linalg.solve(chol, eye), 1, 2)           # (L^-1)^T: (x - mu) @ W is white
        self._log_const = (np.log(self.weights) - 0.5 * d * np.log(2 * np.pi)
                           - np.sum(np.log(np.diagonal(chol, axis1=1, axis2=2)), axis=1))
        # every component's whitening side by side, so that scoring a block is one matrix product
        self._whiten_all = np.concatenate(list(whiten), axis=1)                          # (d, k d)
        self._shift_all = np.einsum("kd,kde->ke", self.means, whiten).reshape(-1)

    @property
    def n_components(self) -> int:
        return int(self.weights.shape[0])

    # --- scoring -------------------------------------------------------------------------------
    def log_likelihood_features(self, feats: np.ndarray) -> np.ndarray:
        """Log density (...) of features (..., 48); NaN features give NaN."""
        feats = np.asarray(feats, dtype=float)
        flat = feats.reshape(-1, feats.shape[-1])
        out = np.empty(flat.shape[0])
        k, d = self.means.shape
        for a in range(0, flat.shape[0], BLOCK):
            y = (flat[a:a + BLOCK] @ self._whiten_all - self._shift_all).reshape(-1, k, d)
            log_p = self._log_const - 0.5 * np.einsum("nkd,nkd->nk", y, y)
            top = np.max(log_p, axis=1, keepdims=True)
            out[a:a + BLOCK] = top[:, 0] + np.log(np.sum(np.exp(log_p - top), axis=1))
        return out.reshape(feats.shape[:-1])

    def log_likelihood_bones(self, bones: np.ndarray, up: np.ndarray | None = None) -> np.ndarray:
        """Log density (...) of poses given as bone vectors (..., 16, 3)."""
        return self.log_likelihood_features(features_from_bones(bones, up, self.bones))

    def log_likelihood(self, joints: np.ndarray, up: np.ndarray | None = None) -> np.ndarray:
        """Log density (...) of poses (..., 17, 3), in any axes (the body's frame removes them)."""
        return self.log_likelihood_bones(bone_vectors(joints), up)

    def rate_log_likelihood(self, joints: np.ndarray, fps: float) -> np.ndarray:
        """Log density (F-1,) of the change between consecutive poses (F, 17, 3) at ``fps``."""
        f = features_from_bones(bone_vectors(joints), None, self.bones)
        rate = np.diff(f, axis=0) * float(fps) / self.rate_sigma
        d = rate.shape[-1]
        return (-0.5 * np.sum(rate * rate, axis=-1) - np.sum(np.log(self.rate_sigma)) - 0.5 * d * np.log(2 * np.pi)
                + d * np.log(float(fps)))

    def flip_gains(self, joints: np.ndarray, depth_axis: np.ndarray | None = None) -> np.ndarray:
        """(F, 16): log density with each bone's depth sign flipped, minus as it is (> 0: the flip is likelier).

        ``joints`` (F, 17, 3) in the camera's axes (depth = z), or give ``depth_axis`` (F, 3) or (3,)
        unit viewing directions.  A bone's two depth choices differ by the sign of its vector's
        component along the view, so the flip reflects that one vector and keeps every other."""
        bones = bone_vectors(joints)
        n = bones.shape[0]
        axis = np.array([0.0, 0.0, 1.0]) if depth_axis is None else np.asarray(depth_axis, dtype=float)
        axis = np.broadcast_to(axis, (n, 3))
        base = self.log_likelihood_bones(bones)
        flipped = np.repeat(bones[:, None], bones.shape[1], axis=1)           # (F, 16 flips, 16 bones, 3)
        idx = np.arange(bones.shape[1])
        along = np.sum(bones * axis[:, None], axis=-1)                         # (F, 16)
        flipped[:, idx, idx] -= 2.0 * along[..., None] * axis[:, None]
        return self.log_likelihood_bones(flipped) - base[:, None]

    def restricted(self, bones) -> PosePrior:
        """The prior over a subset of its bones (a Gaussian mixture's marginal: the other features dropped)."""
        keep = [self.bones.index(int(b)) for b in bones]
        cols = np.ravel([[3 * i, 3 * i + 1, 3 * i + 2] for i in keep])
        meta = dict(self.meta, bones=[int(b) for b in bones])
        return PosePrior(self.weights, self.means[:, cols], self.covariances[:, cols][:, :, cols],
                         self.rate_sigma[cols], meta)

    # --- storage -------------------------------------------------------------------------------
    def save(self, path: str | os.PathLike) -> None:
        """Write the prior as a compressed ``.npz`` (float32 arrays, the metadata as JSON text)."""
        meta = dict(self.meta, format=FORMAT, version=VERSION)
        tmp = os.fspath(path) + ".tmp.npz"
        np.savez_compressed(tmp, weights=self.weights, means=self.means.astype(np.float32),
                            covariances=self.covariances.astype(np.float32),
                            rate_sigma=self.rate_sigma.astype(np.float32), meta=np.array(json.dumps(meta, indent=1)))
        os.replace(tmp, path)

    @classmethod
    def load(cls, path: str | os.PathLike) -> PosePrior:
        """Read a prior written by :meth:`save` (numpy only, no pickles)."""
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            if meta.get("format") != FORMAT:
                raise ValueError(f"{os.fspath(path)}: not a pose prior file")
            cov = data["covariances"].astype(float)
            cov = 0.5 * (cov + np.swapaxes(cov, 1, 2))
            return cls(data["weights"], data["means"], cov, data["rate_sigma"], meta)
