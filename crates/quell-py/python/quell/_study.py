"""quell.StudyResult: a sweep's rows with the study they came from, so that any run (the worst, say)
can be simulated again in one call."""

import re

from ._errors import ScenarioError, a_type

#: The figures of a row, one column per channel (``tail_max_e1``, ``tail_max_e2``, …).
METRICS = ("tail_max_e", "tail_rms_e", "max_u", "max_uf", "settle_t")


class StudyResult:
    """The rows of a sweep (``Study.sweep``) and the study they came from.

    Parameters
    ----------
    study : Study
        The study that was swept.
    frame : pandas.DataFrame
        Its rows: the columns of runs.csv, then the drawn values.

    Raises
    ------
    TypeError
        ``study`` is not a Study or ``frame`` not a DataFrame.

    Attributes
    ----------
    study : Study
        The study.
    frame : pandas.DataFrame
        One row per run, in run order: ``run, point, draw, seed``, the grid values, ``outcome``,
        ``reason``, per channel ``tail_max_e, tail_rms_e, max_u, max_uf, settle_t``, ``steps``,
        ``wall_ms``, then one column per drawn number (``truth.delays[1]``, ``truth.A[0][2]``), as
        the CLI's runs.csv.
    partial : bool
        True when Ctrl-C stopped the sweep: the rows are those of the runs carried out (the
        KeyboardInterrupt's ``.result``); ``frame.attrs["partial"]`` holds the same.

    Examples
    --------
    >>> study = quell.Study(quell.paper_example(), simulation={"t_end": 2.0},
    ...                     grid={"design.beta": [1.0, 2.0]})
    >>> result = study.sweep(jobs=1)
    >>> len(result), list(result.frame["design.beta"])
    (2, [1.0, 2.0])
    """

    def __init__(self, study, frame):
        from ._quell import Study

        if not isinstance(study, Study):
            raise TypeError(f"study: expected a quell.Study, found {a_type(study)}")
        if not all(hasattr(frame, a) for a in ("columns", "iloc", "to_numpy")):
            raise TypeError(f"frame: expected a pandas DataFrame, found {a_type(frame)}")
        self.study = study
        self.frame = frame

    def __len__(self):
        return len(self.frame)

    @property
    def partial(self):
        """Whether Ctrl-C stopped the sweep before every run (``frame.attrs["partial"]``)."""
        return bool(self.frame.attrs.get("partial", False))

    def __repr__(self):
        counts = self.frame["outcome"].value_counts().to_dict() if len(self.frame) else {}
        return f"StudyResult(runs={len(self.frame)}, outcomes={counts!r})"

    def __eq__(self, other):
        """Equal results: the same study and the same rows (wall times included)."""
        if not isinstance(other, StudyResult):
            return NotImplemented
        return self.study == other.study and self.frame.equals(other.frame)

    __hash__ = None  # type: ignore[assignment]  # mutable: a frame is not hashable

    def to_pandas(self):
        """The rows as a pandas DataFrame (a copy of ``frame``).

        Returns
        -------
        pandas.DataFrame
            One row per run.

        Raises
        ------
        ImportError
            pandas is not installed.

        Examples
        --------
        >>> result = quell.Study(quell.paper_example(), simulation={"t_end": 2.0}).sweep(jobs=1)
        >>> result.to_pandas()["outcome"].tolist()
        ['completed']
        """
        return self.frame.copy()

    def rerun(self, run):
        """Simulates run ``run`` again, as the sweep did, and returns its signals.

        Parameters
        ----------
        run : int
            The run index (the ``run`` column; negative counts from the end).

        Returns
        -------
        SimResult
            The run's signals, however it ended (a diverged run is returned, not raised).

        Raises
        ------
        TypeError
            ``run`` is not an int.
        IndexError
            ``run`` is not a run of the study.

        Examples
        --------
        >>> study = quell.Study(quell.paper_example(), simulation={"t_end": 2.0})
        >>> result = study.sweep(jobs=1)
        >>> r = result.rerun(0)
        >>> bool(r.summary()[0]["tail_max_e"] == result.frame["tail_max_e1"][0])
        True
        """
        return self.study.spec(run).simulate()

    def worst(self, metric="tail_max_e"):
        """The worst row by ``metric``: its largest value, a run that did not complete (diverged,
        failed or stopped: the peaks it keeps are a runaway's) or has no figure (not settled, for ``settle_t``)
        counting as worse than any; the first on ties.

        Parameters
        ----------
        metric : str
            A figure of the rows: ``tail_max_e``, ``tail_rms_e``, ``max_u``, ``max_uf`` or
            ``settle_t`` (the largest over the channels), or one channel's column
            (``tail_max_e2``).

        Returns
        -------
        pandas.Series
            The row (``row["run"]`` is its run index).

        Raises
        ------
        TypeError
            ``metric`` is not a str.
        ScenarioError
            ``metric`` is not a figure of the rows, or the study has no rows.

        Examples
        --------
        >>> study = quell.Study(quell.paper_example(), simulation={"t_end": 2.0},
        ...                     grid={"design.mu[0]": [1.0, 20.0]})
        >>> row = study.sweep(jobs=1).worst("tail_max_e1")
        >>> int(row["run"]), float(row["design.mu[0]"])
        (0, 1.0)
        """
        import numpy as np

        values = self._metric(metric)
        if len(values) == 0:
            raise ScenarioError("metric: the study has no rows")
        ranked = np.where(np.isnan(values), np.inf, values)
        return self.frame.iloc[int(np.argmax(ranked))]

    def rerun_worst(self, metric="tail_max_e"):
        """Simulates the worst run by ``metric`` again (see ``worst``): ``rerun(worst(metric)["run"])``.

        Parameters
        ----------
        metric : str
            As in ``worst``.

        Returns
        -------
        SimResult
            The worst run's signals, however it ended.

        Raises
        ------
        TypeError
            ``metric`` is not a str.
        ScenarioError
            ``metric`` is not a figure of the rows.

        Examples
        --------
        >>> study = quell.Study(quell.paper_example(), simulation={"t_end": 2.0},
        ...                     grid={"design.mu[0]": [1.0, 20.0]})
        >>> result = study.sweep(jobs=1)
        >>> r = result.rerun_worst("tail_max_e1")
        >>> bool(r.summary()[0]["tail_max_e"] == result.frame["tail_max_e1"].max())
        True
        """
        return self.rerun(int(self.worst(metric)["run"]))

    def _metric(self, metric):
        """Per row, the value of ``metric``: NaN where the row has none, and for a run that did not
        complete (a diverged run keeps the peaks it reached, which would rank it below completed ones)."""
        import numpy as np

        if not isinstance(metric, str):
            raise TypeError(f"metric: expected a str (a figure such as 'tail_max_e'), found {a_type(metric)}")
        m = self.study.m
        if metric in METRICS:
            columns = [f"{metric}{i}" for i in range(1, m + 1)]
        elif re.fullmatch(r"(%s)[1-9][0-9]*" % "|".join(METRICS), metric) and metric in self.frame.columns:
            columns = [metric]
        else:
            names = ", ".join(METRICS)
            columns = f"{METRICS[0]}1" if m == 1 else f"{METRICS[0]}1 … {METRICS[0]}{m}"
            raise ScenarioError(
                f"metric: expected one of {names} (the largest over the channels) or one channel's column "
                f"such as {columns}, found {metric!r}"
            )
        values = self.frame[columns].to_numpy(dtype=float)
        missing = np.isnan(values).any(axis=1) | (self.frame["outcome"] != "completed").to_numpy()
        return np.where(missing, np.nan, np.nanmax(np.where(np.isnan(values), -np.inf, values), axis=1))
