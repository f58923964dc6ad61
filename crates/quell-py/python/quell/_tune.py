"""quell.TuneResult: what ``quell.tune`` found, with every evaluation as a DataFrame (the columns of
``quell tune``'s tune.csv)."""

import json as _json

from ._errors import ScenarioError, a_type

#: The columns of ``TuneResult.frame``, those of tune.csv.
COLUMNS = ("channel", "mu", "objective", "outcome", "reason", "tail_max_e", "tail_rms_e", "max_u", "max_uf",
           "settle_t", "chosen")
FIGURES = ("tail_max_e", "tail_rms_e", "max_u", "max_uf", "settle_t")


class TuneResult:
    """The result of ``quell.tune``: each channel's search, the tuned μ and the joint run's check.

    Parameters
    ----------
    json : str
        The library's result as JSON (what ``quell tune`` writes to tune.json).

    Raises
    ------
    TypeError
        ``json`` is not a str.
    ScenarioError
        ``json`` is not a tuning result.

    Attributes
    ----------
    objective : str
        What the searches minimized: "settle_t", "tail_rms_e" or "tail_max_e".
    mu : list of float
        The tuned μ (the scenario's μ_i where a channel had no feasible point).
    feasible : list of bool
        Per channel, whether some μ in its bounds was feasible (``quell.tune`` warns of each that
        was not, as ``quell tune`` exits 2).
    reproduced : list of bool
        Per channel, whether the joint run (every μ_i tuned at once) reproduced the search's
        objective within tolerance (Proposition 1's decoupling); all False when ``partial``.
    within_limits : list of bool or None
        Per channel, whether the joint run kept max |u_i| and max |u_f,i| within ``max_u`` and
        ``max_uf`` (u_f mixes every channel's command, so limits met in each search can be broken
        together); all None when ``partial`` (nothing was checked).
    joint_difference : list of float or None
        Per channel, the joint run's objective minus the search's.
    joint : dict or None
        The joint run's row (runs.csv's fields), None when the tuning was interrupted before it.
    ties : list of dict or None
        Per channel, what its chosen μ ties with: ``least`` (the least objective of its curve),
        ``mu`` (where) and ``bound`` (objectives up to it tie); None where no μ was feasible.
    partial : bool
        True when Ctrl-C stopped the tuning: the curves hold the points evaluated so far and
        ``mu`` is chosen from them (the least μ within the solver's error of the best).

    Examples
    --------
    >>> r = quell.tune(quell.paper_example(), mu=[5.0, 80.0], points=3, refine=0,
    ...                simulation={"t_end": 10.0}, jobs=1)
    >>> quell.TuneResult(r.to_json()) == r
    True
    """

    def __init__(self, json):
        if not isinstance(json, str):
            raise TypeError(f"json: expected a str (a tuning result as JSON), found {a_type(json)}")
        try:
            data = _json.loads(json)
            self.objective = data["objective"]
            self._channels = data["channels"]
            self.mu = list(data["mu"])
            self.joint = data["joint"]
            self.joint_difference = list(data["joint_difference"])
            self.reproduced = list(data["reproduced"])
            self.within_limits = list(data.get("within_limits", []))
            self.partial = bool(data.get("partial", False))
            self.feasible = [c.get("chosen") is not None for c in self._channels]
            self.ties = [c.get("tie") for c in self._channels]
            if not isinstance(self.objective, str) or not all(isinstance(v, (int, float)) for v in self.mu):
                raise TypeError("objective is not a str or mu not numbers")
            list(self._rows())  # every channel's curve readable now, not at the first frame
        except (ValueError, KeyError, TypeError, AttributeError) as e:
            raise ScenarioError(f"json: not a quell tuning result ({e!r})") from None
        self._json = json

    def to_json(self):
        """The result as JSON, tune.json's form.

        Returns
        -------
        str
            JSON; ``quell.TuneResult(r.to_json())`` rebuilds the result.

        Raises
        ------
        This method raises nothing.

        Examples
        --------
        >>> r = quell.tune(quell.paper_example(), mu=[5.0, 80.0], points=2, refine=0,
        ...                simulation={"t_end": 5.0}, jobs=1)
        >>> '"objective":"settle_t"' in r.to_json()
        True
        """
        return self._json

    def _rows(self):
        for c in self._channels:
            chosen = c.get("chosen")
            for p in c["curve"]:
                figures = p.get("figures") or {}
                row = {"channel": c["channel"], "mu": p["mu"], "objective": p["objective"],
                       "outcome": p["outcome"], "reason": p.get("reason") or float("nan")}
                row.update({f: figures.get(f) for f in FIGURES})
                row["chosen"] = chosen is not None and chosen["mu"] == p["mu"]
                yield row

    @property
    def frame(self):
        """Every evaluation, one row each, by channel and μ: tune.csv's columns ``channel`` (from 1),
        ``mu``, ``objective`` (None where infeasible), ``outcome``, ``reason`` (why a run did not
        complete, as runs.csv's; NaN for a completed run, as a sweep's frame and tune.csv read by
        pandas have it), the channel's figures and ``chosen``; ``attrs["partial"]`` as a sweep's
        frame has it (True after Ctrl-C)."""
        import pandas as pd

        frame = pd.DataFrame(list(self._rows()), columns=list(COLUMNS))
        frame["reason"] = frame["reason"].astype(object)  # text, also where every run completed
        frame.attrs["partial"] = self.partial
        return frame

    @property
    def best(self):
        """The chosen evaluation of each channel that had a feasible one (rows of ``frame``)."""
        frame = self.frame
        return frame[frame["chosen"]].reset_index(drop=True)

    def __len__(self):
        return sum(len(c["curve"]) for c in self._channels)

    def __eq__(self, other):
        """Equal results: the same JSON (every evaluation, the joint run's wall time included)."""
        if not isinstance(other, TuneResult):
            return NotImplemented
        return self._json == other._json

    __hash__ = None  # type: ignore[assignment]  # compared by value; not meant as a key

    def __repr__(self):
        mu = "[" + ", ".join(f"{m:.6g}" for m in self.mu) + "]"
        return f"TuneResult(objective={self.objective!r}, mu={mu}, evaluations={len(self)}, partial={self.partial})"
