"""scikit-learn estimator conventions without importing scikit-learn.

Every model class of :mod:`motion_envs.models` follows scikit-learn's estimator API:

* its ``__init__`` only stores its keyword parameters, unchanged, as attributes of the
  same name (validated, never converted), so :meth:`Estimator.get_params`,
  :meth:`Estimator.set_params` and :func:`sklearn.base.clone` work;
* ``fit(X, y)`` takes scikit-learn's order, ``X`` the inputs of a movement (its
  conditions, start and end, labels or predictors, one row per movement) and ``y`` the
  movements (one recording per row of ``X``); it returns ``self`` and sets fitted
  attributes whose names end in ``_``;
* using a model before ``fit`` raises :class:`NotFittedError`;
* ``predict`` answers with the model's output;
* ``score(X, y)`` is the negative of the papers' criterion (median over the movements
  of the largest error over time), so that greater is better as scikit-learn's model
  selection expects;
* :meth:`Estimator.__sklearn_tags__` gives scikit-learn (>= 1.6) the tags it asks every
  estimator for, so that ``clone``, ``check_is_fitted``, ``Pipeline``, ``GridSearchCV``
  and ``cross_val_score`` take the models (``docs/models.md``).

scikit-learn is an optional extra (``motion-envs[learned]``) and is imported only inside
``__sklearn_tags__``, which only scikit-learn calls. :class:`NotFittedError` subclasses
``ValueError`` and ``AttributeError``, as ``sklearn.exceptions.NotFittedError`` does;
when scikit-learn has been imported, the error raised is also an instance of
scikit-learn's ``NotFittedError``, so either ``except`` clause catches it.
"""

from __future__ import annotations

import inspect
import sys
from typing import Any, TypeVar

__all__ = ["Estimator", "NotFittedError", "check_is_fitted", "not_fitted_error"]

E = TypeVar("E", bound="Estimator")


class NotFittedError(ValueError, AttributeError):
    """A model was used before ``fit`` (or ``load``)."""


_BOTH: dict[type, type[NotFittedError]] = {}


def not_fitted_error(estimator: object, hint: str = "call fit() first") -> NotFittedError:
    """The :class:`NotFittedError` for ``estimator`` (also scikit-learn's when imported)."""
    message = f"this {type(estimator).__name__} is not fitted yet; {hint}"
    exceptions = sys.modules.get("sklearn.exceptions")
    theirs = getattr(exceptions, "NotFittedError", None)
    if isinstance(theirs, type) and issubclass(theirs, BaseException):
        if theirs not in _BOTH:
            _BOTH[theirs] = type("NotFittedError", (NotFittedError, theirs), {})
        return _BOTH[theirs](message)
    return NotFittedError(message)


def check_is_fitted(estimator: object, attribute: str, hint: str = "call fit() first") -> None:
    """Raise :func:`not_fitted_error` unless ``estimator`` has the fitted ``attribute``."""
    if attribute not in vars(estimator):
        raise not_fitted_error(estimator, hint)


class Estimator:
    """``get_params``/``set_params``/``repr`` from the ``__init__`` signature (sklearn's)."""

    @classmethod
    def _get_param_names(cls) -> list[str]:
        init = cls.__init__
        if init is object.__init__:
            return []
        params = inspect.signature(init).parameters.values()
        for p in params:
            if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
                raise TypeError(f"{cls.__name__}.__init__ must not take *args or **kwargs")
        return sorted(p.name for p in params if p.name != "self")

    def get_params(self, deep: bool = True) -> dict[str, Any]:
        """The constructor parameters (and, with ``deep``, those of nested estimators)."""
        out: dict[str, Any] = {}
        for name in self._get_param_names():
            value = getattr(self, name)
            if deep and hasattr(value, "get_params") and not isinstance(value, type):
                out.update((f"{name}__{k}", v) for k, v in value.get_params().items())
            out[name] = value
        return out

    def set_params(self: E, **params: Any) -> E:
        """Set constructor parameters (``nested__name`` for nested ones); returns ``self``.

        The new values are validated by building a fresh instance with them.
        """
        if not params:
            return self
        valid = self.get_params(deep=True)
        nested: dict[str, dict[str, Any]] = {}
        own: dict[str, Any] = {}
        for key, value in params.items():
            name, _, sub = key.partition("__")
            if name not in valid:
                raise ValueError(
                    f"invalid parameter {name!r} for {type(self).__name__}; "
                    f"valid parameters: {sorted(self._get_param_names())}"
                )
            if sub:
                nested.setdefault(name, {})[sub] = value
            else:
                own[name] = value
        if own:
            current = self.get_params(deep=False)
            type(self)(**{**current, **own})  # validate with the constructor's checks
            for name, value in own.items():
                setattr(self, name, value)
        for name, sub_params in nested.items():
            valid[name].set_params(**sub_params)
        return self

    def __sklearn_tags__(self) -> Any:
        """The tags scikit-learn asks every estimator for (``sklearn.utils.get_tags``).

        scikit-learn's defaults for an estimator that needs ``fit`` and a target: ``y``
        (the movements) is required; no estimator type (the models are neither
        classifiers nor regressors of a scalar target), so model selection uses
        :meth:`score`. Imported here, on call: only scikit-learn calls it.
        """
        from sklearn.utils import Tags, TargetTags

        return Tags(estimator_type=None, target_tags=TargetTags(required=True))

    def __repr__(self) -> str:
        init = inspect.signature(type(self).__init__).parameters
        shown = []
        for name, value in self.get_params(deep=False).items():
            default = init[name].default
            try:
                same = bool(value == default) if default is not inspect.Parameter.empty else False
            except (TypeError, ValueError):
                same = False
            if not same:
                shown.append(f"{name}={value!r}")
        return f"{type(self).__name__}({', '.join(shown)})"
