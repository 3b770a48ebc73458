"""DriftRegressor: thermodrift's fit as a scikit-learn estimator.

``X`` is a chamber log as a DataFrame (``td.read_log``'s); the target is in it (the gyro
columns), so ``y`` is ignored. ``predict`` returns the drift of every row and axis, which
scikit-learn's tools (``clone``, pipelines, ``cross_validate`` with blocked splits such as
``TimeSeriesSplit``) take like any regressor's output.
"""

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin

from . import fit as _fit


class DriftRegressor(RegressorMixin, BaseEstimator):
    """One drift model per gyro axis (``thermodrift fit``), fitted on a DataFrame.

    Parameters are ``fit``'s keywords; ``options`` takes any other option of
    ``thermodrift fit`` as a dict (``{"rate_span": 50}``).
    """

    def __init__(self, model="linear", features=None, seed=1, smooth=100.0, C=None, sigma=None, epsilon=None,
                 evaluations=None, threads=0, gyro=None, temp=None, options=None, progress=False):
        self.model = model
        self.features = features
        self.seed = seed
        self.smooth = smooth
        self.C = C
        self.sigma = sigma
        self.epsilon = epsilon
        self.evaluations = evaluations
        self.threads = threads
        self.gyro = gyro
        self.temp = temp
        self.options = options
        self.progress = progress

    def fit(self, X, y=None):
        keywords = dict(smooth=self.smooth, C=self.C, sigma=self.sigma, epsilon=self.epsilon,
                        evaluations=self.evaluations, threads=self.threads or None, gyro=self.gyro, temp=self.temp)
        keywords = {k: v for k, v in keywords.items() if v is not None}
        keywords.update(self.options or {})
        self.model_ = _fit(X, model=self.model, features=self.features, seed=self.seed, progress=self.progress,
                           **keywords)
        self.axes_ = self.model_.axes
        self.n_features_in_ = X.shape[1]
        return self

    def predict(self, X):
        """The drift (°/h) of every row: shape (rows, axes), or (rows,) for one axis."""
        drift = self.model_.drift(X, gyro=self.gyro, temp=self.temp).to_numpy()
        return drift[:, 0] if drift.shape[1] == 1 else drift

    def score(self, X, y=None, sample_weight=None):
        """Minus the mean over the axes of the MSE left after compensation (°/h)², on the
        smoothed rates as ``evaluate`` measures it: higher is better. ``y`` is ignored."""
        result = self.model_.evaluate(X, gyro=self.gyro, temp=self.temp)
        return -float(np.mean([axis["mse_after"] for axis in result["axes"]]))
