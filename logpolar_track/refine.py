"""Gradient refinement of a similarity (centre, scale, angle) against a subspace model of appearance.

The thesis lists both as future work for its log-polar trackers: a gradient refinement of the final estimate,
and a subspace (PCA) model of the object's appearance. They fit together as in EigenTracking (M. J. Black and
A. D. Jepson, IJCV 1998) and IVT (D. A. Ross, J. Lim, R.-S. Lin, M.-H. Yang, IJCV 2008): the object's patch,
sampled in its own frame, should lie in a low-dimensional subspace of its past appearances; the Gauss-Newton
step moves the sampling frame to bring it closer. Errors and gradients are projected out of the subspace
before the step is solved (G. D. Hager and P. N. Belhumeur, PAMI 1998; S. Baker and I. Matthews, "Lucas-Kanade
20 years on", IJCV 2004), so appearance that the subspace explains -- a brightness offset or gain, a known
change of expression -- is not taken for motion.

Conventions: patches are sampled on a grid of ``(h, w)`` samples in the object's frame, sample ``(p, q)`` at
offset ``(u, v) = (p - w / 2, q - h / 2)`` samples from the centre (as in an FFT-centred patch), ``u`` along
the object's x axis and ``v`` along its y axis (down on screen when the object is not turned). A step is
``(du, dv, d_log_scale, d_angle)``: the centre moved by ``(du, dv)`` samples in that frame, the scale
multiplied by ``exp(d_log_scale)``, and the sampling grid turned by ``d_angle`` radians, positive turning
``u`` towards ``-v`` (counter-clockwise on screen, y down).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .errors import UsageError


class AppearanceSubspace:
    """The object's appearance as a linear subspace of weighted, high-passed patches.

    Spanned by a constant (so that a change of brightness is not an error), the first frame's patch (an anchor
    that cannot drift), the mean of the last ``memory`` patches added and, with ``n_components`` > 0, their
    leading principal components. Patches are high-passed, flattened and multiplied by the square root of the
    sample weights before anything else, so that plain Euclidean norms are the weighted ones.

    Parameters
    ----------
    first : ndarray, shape (h, w)
        The first frame's patch (grey levels).
    sqrt_weights : ndarray, shape (h, w)
        Square roots of the per-sample weights (0 outside the object; the outermost samples must be 0, where
        the gradients are one-sided).
    n_components : int
        Principal components of the recent patches kept (0: their mean only).
    memory : int
        Recent patches kept for the mean and the components.
    refresh : int
        The subspace is recomputed every ``refresh`` patches added (the eigenvectors of the recent patches'
        ``(memory, memory)`` Gram matrix and a QR decomposition, about 0.15 ms for 34 x 34 patches).
    highpass_sigma : float
        Patches are compared after subtracting a Gaussian blur of this many samples (0: as they are), so that
        smooth changes of lighting across the object (a spotlight, a shadow's soft edge) are not taken for
        motion.

    Attributes
    ----------
    basis : ndarray, shape (h w, k)
        Orthonormal basis of the subspace, float32, in weighted coordinates (k <= n_components + 3).
    anchor_basis : ndarray, shape (h w, k)
        The same for the constant and the first frame's patch alone (k <= 2): the part that cannot drift.
    u, v : ndarray, shape (h w,)
        Offsets of the samples from the patch's centre, in samples (see the module's conventions).
    """

    def __init__(self, first: np.ndarray, sqrt_weights: np.ndarray, *, n_components: int = 4, memory: int = 16,
                 refresh: int = 4, highpass_sigma: float = 2.0):
        if first.shape != sqrt_weights.shape or first.ndim != 2:
            raise UsageError(f"first patch {first.shape} and weights {sqrt_weights.shape} must be one 2-D shape")
        if not 0 <= n_components < memory or refresh < 1 or highpass_sigma < 0:
            raise UsageError(f"need 0 <= n_components < memory, refresh >= 1 and highpass_sigma >= 0, got "
                             f"{n_components}, {memory}, {refresh}, {highpass_sigma}")
        self.shape = first.shape
        self.sqrt_weights = sqrt_weights.astype(np.float32).ravel()
        self.n_components, self.memory, self.refresh = n_components, memory, refresh
        self.highpass_sigma = float(highpass_sigma)
        h, w = first.shape
        v, u = np.mgrid[:h, :w].astype(np.float32)
        self.u, self.v = (u - w / 2.0).ravel(), (v - h / 2.0).ravel()
        self._constant = self._unit(self.sqrt_weights.copy())
        first_x = self._weighted(self.prepared(first))
        self._first_varying = float(np.linalg.norm(first_x - self._constant * float(self._constant @ first_x)))
        self._first = self._normalised(first)
        self._recent: list[np.ndarray] = []
        self._added = 0
        self.basis = self.anchor_basis = self._orthonormal([self._constant, self._first])

    def add(self, patch: np.ndarray) -> None:
        """Add a patch ``(h, w)`` of the object (grey levels) to the recent ones."""
        self._recent.append(self._normalised(patch))
        del self._recent[:-self.memory]
        self._added += 1
        if self._added % self.refresh == 0 or len(self._recent) == 1:
            self.basis = self._orthonormal([self._constant, self._first] + self._summary())

    def distance(self, patch: np.ndarray) -> float:
        """Relative distance (0 to 1) of a patch ``(h, w)`` from the subspace: the weighted norm of its part
        outside the subspace over that of its part that is not constant."""
        return self._distance(self._weighted(self.prepared(patch)))

    def prepared(self, patch: np.ndarray) -> np.ndarray:
        """The patch as compared, ``(h, w)`` float32: high-passed with ``highpass_sigma``."""
        patch = np.asarray(patch, np.float32)
        if self.highpass_sigma > 0:
            patch = patch - cv2.GaussianBlur(patch, (0, 0), self.highpass_sigma, borderType=cv2.BORDER_REPLICATE)
        return patch

    def _distance(self, x: np.ndarray, outside: np.ndarray | None = None, varying: float | None = None) -> float:
        """:meth:`distance` of a weighted patch ``x``, given its part ``outside`` the subspace and its
        :meth:`_varying` norm if known."""
        if outside is None:
            outside = x - self.basis @ (self.basis.T @ x)
        if varying is None:
            varying = self._varying(x)
        if varying <= _FLAT * self._first_varying:
            return 1.0  # a featureless patch (off the frame, a flat cover) is not the object
        return math.sqrt(float(outside @ outside)) / varying

    def _varying(self, x: np.ndarray) -> float:
        """Weighted norm of the part of a weighted patch ``x`` that is not constant."""
        constant_part = float(self._constant @ x)
        return math.sqrt(max(float(x @ x) - constant_part * constant_part, 0.0))

    def _summary(self) -> list[np.ndarray]:
        stacked = np.stack(self._recent, axis=1)
        mean = stacked.mean(axis=1)
        if self.n_components == 0 or len(self._recent) < 2:
            return [mean]
        # Leading left singular vectors of the centred patches, from the eigenvectors of their small Gram
        # matrix (memory x memory): the same directions as a singular value decomposition, at a tenth of its cost.
        centred = stacked - mean[:, None]
        values, vectors = np.linalg.eigh(centred.T @ centred)
        top = np.argsort(values)[::-1][:self.n_components]
        top = top[values[top] > 1e-6 * max(float(values.max()), 1e-12)]
        # Where the recent views differ mostly by the tracker's own small misalignment (a rigid object), the
        # components lean towards the motion directions and shrink the steps (a 1 px offset read as 0.3 px in
        # one step; the second step makes up most of it). Taking the motion directions out of the components
        # made the steps whole but cost the lighting sample (median scale error 1.2 % -> 2.1 %), so they stay.
        return [mean] + list((centred @ vectors[:, top]).T)

    def _weighted(self, prepared: np.ndarray) -> np.ndarray:
        return prepared.ravel() * self.sqrt_weights

    def _normalised(self, patch: np.ndarray) -> np.ndarray:
        """The weighted patch with its constant part removed, at unit norm: patches of every contrast count
        alike."""
        x = self._weighted(self.prepared(patch))
        return self._unit(x - self._constant * float(self._constant @ x))

    @staticmethod
    def _unit(x: np.ndarray) -> np.ndarray:
        return x / (float(np.linalg.norm(x)) + 1e-9)

    @staticmethod
    def _orthonormal(columns: list[np.ndarray]) -> np.ndarray:
        # The columns as the transpose of their rows, not stacked column-wise (a strided copy): the same matrix, which
        # the QR reads into its own Fortran-order buffer either way.
        q, r = np.linalg.qr(np.array(columns).T)
        # Columns that added nothing new (a patch equal to the first) would bring noise directions: drop them.
        keep = np.abs(np.diag(r)) > 1e-4 * max(float(np.abs(np.diag(r)).max()), 1e-12)
        return np.ascontiguousarray(q[:, keep], dtype=np.float32)


def similarity_step(patch: np.ndarray, subspace: AppearanceSubspace, damping: float = 1e-3,
                    anchor_below: float = 0.0) -> tuple[np.ndarray, float]:
    """One Gauss-Newton step towards the appearance subspace, and the patch's distance from it before the step.

    Parameters
    ----------
    patch : ndarray, shape (h, w)
        The object's patch sampled at the current estimate (grey levels; see the module's conventions).
    subspace : AppearanceSubspace
        The appearance model, with the sample weights.
    damping : float
        Levenberg-Marquardt damping, relative to the mean of the normal matrix's diagonal.
    anchor_below : float
        Where the patch is within this distance (as :meth:`AppearanceSubspace.distance`) of the span of the first
        frame's patch and the constant alone, the step goes towards that span instead (0: never). The recent
        patches in the subspace were sampled at the tracker's own, slightly wrong, poses; for a rigid object their
        mean and components explain part of a misalignment, which the step then does not correct, and the
        estimate drifts (the template update problem: Matthews, Ishikawa and Baker, PAMI 2004). An object that
        still looks as it did on the first frame is aligned to that frame, which cannot drift.

    Returns
    -------
    step : ndarray, shape (4,)
        ``(du, dv, d_log_scale, d_angle)``: samples, samples, natural log, radians (counter-clockwise on
        screen).
    distance : float
        :meth:`AppearanceSubspace.distance` of the patch, at the current estimate (from the whole subspace).
    """
    prepared = subspace.prepared(patch)
    jacobian = _motion_jacobian(prepared, subspace)
    x = subspace._weighted(prepared)
    basis = subspace.basis
    # Project the error and the Jacobian out of the subspace: appearance it explains is not motion. With J' the
    # projected Jacobian, J'^T J' = J^T J - (B^T J)^T (B^T J) and J'^T e' = J^T e' for the projected error e'.
    error = x - basis @ (basis.T @ x)
    varying = subspace._varying(x)  # shared by both distances
    distance = subspace._distance(x, error, varying)
    if anchor_below > 0:
        anchor = subspace.anchor_basis
        anchor_error = x - anchor @ (anchor.T @ x)
        if subspace._distance(x, anchor_error, varying) < anchor_below:
            basis, error = anchor, anchor_error
    in_basis = basis.T @ jacobian
    normal = (jacobian.T @ jacobian - in_basis.T @ in_basis).astype(np.float64)
    diagonal = normal.ravel()[::5]  # a view (normal is contiguous); the same sum as np.trace, a third the cost
    diagonal += damping * float(diagonal.sum()) / 4 + 1e-9
    _, step = cv2.solve(normal, -(jacobian.T @ error[:, None]).astype(np.float64), flags=cv2.DECOMP_CHOLESKY)
    return step.ravel(), distance


def _motion_jacobian(prepared: np.ndarray, subspace: AppearanceSubspace) -> np.ndarray:
    """Weighted ``d(patch)/d(step)`` ``(h w, 4)`` float32 of a prepared patch (see :func:`similarity_step`)."""
    # Central differences, in grey levels per sample (the outermost samples have weight 0), weighted.
    sqrt_w = subspace.sqrt_weights
    grad_u = cv2.Sobel(prepared, cv2.CV_32F, 1, 0, ksize=1, scale=0.5).ravel() * sqrt_w
    grad_v = cv2.Sobel(prepared, cv2.CV_32F, 0, 1, ksize=1, scale=0.5).ravel() * sqrt_w
    u, v = subspace.u, subspace.v
    # Moving the grid by du samples reads the patch du further along u, and so on; a turn by d_angle moves the
    # sample at (u, v) to (u + d_angle v, v - d_angle u) (counter-clockwise on screen).
    jacobian = np.empty((len(u), 4), np.float32)
    jacobian[:, 0] = grad_u
    jacobian[:, 1] = grad_v
    # Products into the columns, then the other products added or taken in place: the same roundings, two
    # temporaries fewer.
    np.multiply(grad_u, u, out=jacobian[:, 2])
    jacobian[:, 2] += grad_v * v
    np.multiply(grad_u, v, out=jacobian[:, 3])
    jacobian[:, 3] -= grad_v * u
    return jacobian


#: A patch whose varying part is below this fraction of the first view's is featureless (distance 1).
_FLAT = 1e-3
