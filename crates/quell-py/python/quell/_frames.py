"""SimResult.to_pandas and SimResult.plot: pandas and matplotlib are imported only here, when used."""

import operator

from ._errors import ScenarioError, a_type


def columns(m, q, n=0):
    """The header of signals.csv: t, y1..ym, g1..gm, e1..em, u1..um, uf1..ufm, eta1_1..etam_q, and
    with recorded states (n > 0) x1..xn, xhat1..xhatn."""
    names = ["t"]
    for signal in ("y", "g", "e", "u", "uf"):
        names += [f"{signal}{i}" for i in range(1, m + 1)]
    names += [f"eta{i}_{j}" for i in range(1, m + 1) for j in range(1, q + 1)]
    for signal in ("x", "xhat") if n else ():
        names += [f"{signal}{i}" for i in range(1, n + 1)]
    return names


def to_pandas(result):
    """The columns of signals.csv as a DataFrame (one row per sample)."""
    try:
        import pandas as pd
    except ImportError as e:
        raise ImportError("SimResult.to_pandas needs pandas: pip install pandas") from e
    import numpy as np

    k, m, q = len(result), result.m, result.q
    blocks = [result.t, result.y, result.g, result.e, result.u, result.u_f, np.asarray(result.eta).reshape(k, m * q)]
    states = result.x is not None
    if states:
        blocks += [result.x, result.x_hat]
    data = np.column_stack(blocks)
    return pd.DataFrame(data, columns=columns(m, q, result.n if states else 0))


# The most η̂ entries a panel's legend names (the CLI's MAX_LEGEND).
MAX_LEGEND = 14

# A reference whose path runs more than this many times its panel's width is drawn as a band.
BAND = 6.0


def _ended(outcome, unit):
    """Where and why a run's curves end, in the CLI's words: "" for a completed run, " (diverged at
    t = 11.16 s: x2 (plant state))", " (interrupted at t = …)", or for a budget or the step size
    " (failed at t = …: result.outcome says why)" (the raw status had read "run history_too_large")."""
    status = outcome.get("status", "completed")
    if status == "completed":
        return ""
    at = f"at t = {outcome['t']:.7g} {unit}"  # seven digits, as the CLI's fmt_instant
    if status == "diverged":
        return f" (diverged {at}: {outcome['signal']})"
    if status == "interrupted":
        return f" (interrupted {at})"
    return f" (failed {at}: result.outcome says why)"


def _path_widths(ax, t, v, shown):
    """The length of the path (t, v) in widths of ``ax``, its value axis spanning ``shown``'s range."""
    import numpy as np

    finite = np.isfinite(t) & np.isfinite(v)
    t, v, shown = t[finite], v[finite], shown[np.isfinite(shown)]
    if t.size < 2:
        return 0.0
    w, h = ax.bbox.width, ax.bbox.height
    dt = np.diff(t) * (w / (np.ptp(t) or 1.0))
    dv = np.diff(v) * (h / (np.ptp(shown) or 1.0))
    return float(np.hypot(dt, dv).sum() / w)


MAX_FIGSIZE = 100
"""The largest width or height, in inches, ``plot`` draws a figure of."""


def plot(result, channel=1, fig=None, ax=None, figsize=None, names=(None, None), u_max=(), u_min=()):
    """Channel ``channel`` (1-based; None is 1) in the six panels of the CLI's figure, like the paper's
    Figs. 1 and 2: y_i with g_i, e_i = y_i - g_i, the command u_i (25), the plant input u_f,i (5),
    eta_i, and the largest |e_i| from each t on (log scale: convergence over decades) against t.

    ``ax``: one matplotlib Axes (then only y_i and g_i are drawn, on it), six (the six panels), five
    (all but the last) or four (u_f,i then shares the third panel on a second y axis of its own
    scale); otherwise a new figure of ``figsize`` (default (10, 16.5)), or the panels are added to
    ``fig``. ``names``: the
    plant's (inputs, outputs) names or None, shown in the titles. ``u_max``, ``u_min``: the true
    actuator's upper and lower limits per input (empty without one; ``u_min`` -u_max where empty),
    drawn on u_f,i's panel where u_f,i comes within a tenth of them and told in the title
    otherwise. Returns the Figure."""
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:
        raise ImportError("SimResult.plot needs matplotlib: pip install matplotlib") from e
    import numpy as np

    m = result.m
    given = 1 if channel is None else channel
    try:
        # An int or numpy's integers, not a bool or a float.
        channel = None if isinstance(given, bool) else operator.index(given)
    except TypeError:
        channel = None
    if channel is None:
        raise TypeError(f"channel: expected an int from 1 to {m}, found {a_type(given)}")
    if not 1 <= channel <= m:
        raise ScenarioError(f"channel: expected a channel number from 1 to {m}, found {channel!r}")
    i, c, t = channel - 1, channel, result.t
    named = lambda given: f" ({given[i]})" if given else ""  # noqa: E731
    channel_title, input_title = f"Channel {c}{named(names[1])}", f"Input {c}{named(names[0])}"
    if figsize is not None and not (
        isinstance(figsize, (tuple, list)) and len(figsize) == 2
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in figsize)
    ):
        found = a_type(figsize)
        if isinstance(figsize, (tuple, list)) and len(figsize) != 2:
            found += f" of {len(figsize)} entries"
        raise TypeError(f"figsize: expected (width, height) in inches, found {found}")
    if figsize is not None and not all(np.isfinite(v) and v > 0 for v in figsize):
        raise ScenarioError(f"figsize: expected (width, height) in inches, both finite and > 0, found {tuple(figsize)!r}")
    # A poster is 50 inches; (300, 300) had taken 3.6 GB drawing at the default dpi.
    if figsize is not None and max(figsize) > MAX_FIGSIZE:
        raise ScenarioError(f"figsize: expected (width, height) of at most {MAX_FIGSIZE} inches each, found {tuple(figsize)!r}; "
                            "for a large image, save the figure at a higher dpi instead")
    if fig is not None and ax is not None:
        raise TypeError("fig and ax: expected one of them or neither (ax's panels belong to a figure already), found both")
    if fig is not None and not hasattr(fig, "subplots"):
        raise TypeError(f"fig: expected a matplotlib Figure, found {a_type(fig)}")
    if fig is not None and fig.axes:
        raise ScenarioError(
            f"fig: expected an empty Figure (the six panels fill it), found one with {len(fig.axes)} Axes; "
            "pass its Axes as ax= (one, four, five or six) or an empty figure"
        )
    if ax is not None:
        axes = list(ax.flat) if hasattr(ax, "flat") else list(ax) if isinstance(ax, (list, tuple)) else [ax]
        if len(axes) not in (1, 4, 5, 6) or not all(hasattr(a, "plot") for a in axes):
            found = f"{len(axes)} entries" if len(axes) not in (1, 4, 5, 6) else "entries that are not Axes"
            if not isinstance(ax, (list, tuple)) and not hasattr(ax, "flat"):
                found = a_type(ax)
            raise TypeError(f"ax: expected one matplotlib Axes, four, five or six, found {found}")
        fig = axes[0].figure
    else:
        fig = fig if fig is not None else plt.figure(figsize=figsize if figsize is not None else (10, 16.5))
        axes = fig.subplots(6, 1, sharex=True)
    # As the CLI's figure: the reference dashed over y, or, when it runs more than BAND times the
    # panel's width (a band, not a line: dashes over it hid the y tracking it), first and faint.
    g, y = result.g[:, i], result.y[:, i]
    if _path_widths(axes[0], t, g, np.concatenate([g, y])) > BAND:
        axes[0].plot(t, g, color="C0", alpha=0.35, linewidth=1, label=f"g{c} (reference)")
        axes[0].plot(t, y, color="C1", label=f"y{c}")
    else:
        axes[0].plot(t, y, color="C1", label=f"y{c}")
        axes[0].plot(t, g, "--", color="C0", label=f"g{c} (reference)")
    # A run that stopped early says so where its curves end.
    ended = _ended(result.outcome, result.time_unit)
    # As the CLI's figure: a sampled-data run says so (at 1 ms its staircases cannot be seen).
    stats = result.stats or {}
    sampled = f", sampled at T_s = {stats['sample_time']:.6g} {result.time_unit}" if stats.get("loop") == "sampled" else ""
    axes[0].set(title=f"{channel_title}: output and reference{sampled}{ended}", ylabel="y, g")
    if len(axes) > 1:
        axes[1].plot(t, result.e[:, i], label=f"e{c}")
        axes[1].set(title=f"{channel_title}: tracking error", ylabel="e = y − g")
        # A sampled run's u and u_f are held between samples (when the hold spans a row).
        held = {"drawstyle": "steps-post"} if result.commands_held else {}
        axes[2].plot(t, result.u[:, i], label=f"u{c}", **held)
        axes[2].set(title=f"{channel_title}: adaptive command (25)", ylabel="u")
        # u_f in a plant's units (newtons, volts) can be 1e5 times u: its own panel, or its own scale.
        if len(axes) >= 5:
            uf_ax = axes[3]
            uf_ax.set(title=f"{input_title}: plant input u_f (5), what the actuator delivers")
        else:
            uf_ax = axes[2].twinx()
            axes[2].set(title=f"{channel_title}: adaptive command (25) and plant input (5, right axis)")
        uf_ax.plot(t, result.u_f[:, i], color="C1", label=f"uf{c}", **held)
        uf_ax.set(ylabel="u_f")
        upper = u_max[i] if i < len(u_max) else np.inf
        lower = u_min[i] if i < len(u_min) else -upper
        if np.isfinite(upper) or np.isfinite(lower):
            title_ax = uf_ax if len(axes) >= 5 else axes[2]
            symmetric = lower == -upper
            uf = result.u_f[:, i][np.isfinite(result.u_f[:, i])]
            # u_f's share of its limits: of u_max above 0, of u_min below.
            share = max((uf[uf >= 0] / upper).max(initial=0.0), (uf[uf < 0] / lower).max(initial=0.0))
            if share >= 0.1:
                label = (f"±truth.u_max[{i}] = {upper:.6g}" if symmetric
                         else f"truth.u_min[{i}], u_max[{i}] = {lower:.6g}, {upper:.6g}")
                for k, level in enumerate(v for v in (upper, lower) if np.isfinite(v)):
                    uf_ax.axhline(level, color="0.35", linestyle="--", linewidth=1,
                                  label=label if k == 0 else None)
            else:
                share = 100 * share
                # Two significant digits below 0.1 %, as the CLI ("0.0 %" hid a peak of 0.0018 %).
                share = f"{share:.2g}".replace("e-0", "e-") if 0 < share < 0.1 else f"{share:.1f}"
                of = "truth.u_max" if symmetric else "truth.u_min, u_max"
                title_ax.set_title(f"{title_ax.get_title()}; peak {share} % of {of}")
            # Where the limit clipped it, how much the controller asked for (summary()'s max_uf).
            asked = result.summary()[i]["max_uf"]
            clipped = (result.limited_fraction or [0.0] * (i + 1))[i] > 0
            if asked is not None and (clipped or asked > max(upper, -lower)):
                # A magnitude: with a range that is not symmetric, which end it neared is not known.
                what = "" if symmetric else "|u_f| "
                title_ax.set_title(f"{title_ax.get_title()}; the controller asked for {what}up to {asked:.4g}")
        eta_ax = axes[4] if len(axes) == 6 else axes[-1]
        # As the CLI's figure: beyond MAX_LEGEND entries a legend hides the traces (q = 33 covered a
        # third of them) and the palette repeats, so the title names the range instead.
        many = result.q > MAX_LEGEND
        for j in range(result.q):
            eta_ax.plot(t, result.eta[:, i, j], label=None if many else f"η{c}_{j + 1}",
                        color=eta_colour(j, result.q))
        eta_title = f"{channel_title}: adjustable parameters (33)"
        if many:
            eta_title += f", η{c}_1 … η{c}_{result.q} from dark blue to yellow"
        eta_ax.set(title=eta_title, ylabel="η")
        if len(axes) == 4:
            uf_ax.legend(loc="best", fontsize="small")
        if len(axes) == 6:
            # max |e_i(s)| over s >= t: the summary's tail figure read from every t on.
            magnitude = np.where(np.isfinite(result.e[:, i]), np.abs(result.e[:, i]), 0.0)
            if ended:
                # As the CLI's panel: a run that stopped early shows |e(t)| itself, its growth (the
                # largest from t on is its last spike's everywhere, a flat line).
                tail, name = magnitude, f"|e{c}(t)|"
                title = f"{channel_title}: tracking error |e(t)|, log scale (the run stopped early: its growth)"
            else:
                tail, name = np.maximum.accumulate(magnitude[::-1])[::-1], f"max |e{c}(s)|, s ≥ t"
                title = f"{channel_title}: largest tracking error from t on, log scale"
            shown = tail > 0
            if shown.any():
                axes[5].semilogy(t[shown], tail[shown], label=name)
                # As the CLI's panel: at most 14 decades, and from when the curve is below them.
                floor = tail.max() * 1e-14
                low = np.nonzero(shown & (tail < floor))[0]
                if low.size:
                    axes[5].set_ylim(bottom=floor)
                    title += f"; below 1e-14 of its peak from t = {t[low[0]]:.6g} {result.time_unit} on"
            else:
                axes[5].set_yscale("log")
                title += ": e ≡ 0"
            axes[5].set(title=title, ylabel="|e|")
    axes[-1].set(xlabel=f"t, {result.time_unit}")
    eta_panel = axes[4] if len(axes) == 6 else axes[-1]
    # As the CLI's figure: a run that ended before its second row has one point per curve, which a
    # line does not draw; a dot does.
    twin = [uf_ax] if len(axes) > 1 and all(uf_ax is not a for a in axes) else []
    for a in list(axes) + twin:
        for line in a.get_lines():
            if len(line.get_xdata()) == 1:
                line.set_marker("o")
    for a in axes:
        a.grid(True, alpha=0.3)
        # Where it hides the least of the curves (a fixed corner covered the η̂ traces); the η̂
        # legend of a figure plot draws beside its panel, as the CLI's (inside, "best" still hid a
        # transient of eleven traces; helper tryout, 2026-12-06).
        labels = a.get_legend_handles_labels()[1]
        if labels and a is eta_panel and ax is None:
            a.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize="small",
                     ncol=1 + (len(labels) > 12))
        elif labels:
            a.legend(loc="best", fontsize="small", ncol=1 + (len(axes) > 1 and a is eta_panel) * 2)
    if ax is None:
        fig.tight_layout()
    return fig


def eta_colour(j, q):
    """The colour of η̂_j+1 of q: matplotlib's cycle up to ten, then twenty distinct ones (the cycle
    had repeated: η_1 and η_11 both blue; helper tryout, 2026-12-06), and beyond the legend's
    fourteen a ramp from dark blue to yellow, which the title names."""
    from matplotlib import colormaps

    if q <= 10:
        return f"C{j}"
    if q <= MAX_LEGEND:
        return colormaps["tab20"](j)
    return colormaps["viridis"](j / (q - 1))


def runs_frame(text):
    """runs.csv's text (quell.sweep) as a DataFrame, read as `pandas.read_csv(path, comment="#")` reads
    the file (its last columns the drawn values)."""
    try:
        import pandas as pd
    except ImportError as e:
        raise ImportError("quell.sweep needs pandas: pip install pandas") from e
    import io

    # `reason` as text even where every run completed (all missing had read as float, and
    # `frame.reason.str` failed on exactly the healthy studies).
    return pd.read_csv(io.StringIO(text), comment="#", dtype={"reason": object})
