"""The FMU of `quell.export(..., fmu=True)`, FMI 2.0 and 3.0, against FMPy, the independent side:
FMPy validates its model description (the FMI 2.0 or 3.0 schema and the standard's rules; for 3.0
also sources/buildDescription.xml) and runs it with its own co-simulation master; the FMU's u_f and
u must be the Controller's and the sampled loop's.

Tolerance 1e-12 (relative to the signal's size): the FMU's binary is the generated C compiled with
-std=c99 -ffp-contract=off, which performs the Controller's operations in its order, so in f64 the
two agree to the last bit; 1e-12 leaves room only for a compiler that contracts a product into a
fused multiply-add, nothing for a wrong index or a sample of delay."""

import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

import quell
from conftest import EXAMPLES


def _closed_loop(path, T, t_end):
    """A scenario's sampled loop, one row per sample, and its FMU."""
    scenario = quell.Scenario.load(path)
    result = quell.simulate(scenario, sample_time=T, t_end=t_end, output_step=T)
    return scenario, result


def _fmu_run(fmu, result, T):
    """FMPy's master steps the FMU at T with the loop's y and g at each sample as inputs."""
    m = result.y.shape[1]
    names = [f"y[{i + 1}]" for i in range(m)] + [f"g[{i + 1}]" for i in range(m)]
    inputs = np.zeros(len(result.t), dtype=[("time", np.float64)] + [(n, np.float64) for n in names])
    inputs["time"] = result.t
    for i in range(m):
        inputs[f"y[{i + 1}]"] = result.y[:, i]
        inputs[f"g[{i + 1}]"] = result.g[:, i]
    outputs = [f"u_f[{i + 1}]" for i in range(m)] + [f"u[{i + 1}]" for i in range(m)]
    return simulate_fmu(
        str(fmu), start_time=0.0, stop_time=result.t[-1], step_size=T, output_interval=T, input=inputs, output=outputs
    )


def _close(a, b):
    scale = max(1.0, float(np.max(np.abs(b))))
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * scale)


# What each version's archive holds besides the model description and the C: FMI 2.0 ships its
# headers; FMI 3.0 (section 2.5) has the importer supply them and lists the sources in
# buildDescription.xml.
LAYOUT = {
    2: ("binaries/linux64/ctrl.so", "sources/fmi2Functions.h"),
    3: ("binaries/x86_64-linux/ctrl.so", "sources/buildDescription.xml"),
}


@pytest.mark.parametrize(
    "example, T, t_end, version",
    [
        ("paper-sampled.toml", 1e-3, 4.0, 2),  # the paper's plant, m = 2, delays 1 s and 3 s
        ("three-channel.toml", 0.05, 20.0, 2),  # m = 3, n = 4, delays 10, 20 and 40 samples
        ("paper-sampled.toml", 1e-3, 4.0, 3),
        ("three-channel.toml", 0.05, 20.0, 3),
    ],
)
def test_fmu_is_the_controller(tmp_path, example, T, t_end, version):
    scenario, result = _closed_loop(EXAMPLES / example, T, t_end)
    written = quell.export(scenario, T, out=tmp_path, fmu=True, fmi_version=version, prefix="ctrl")
    fmu = tmp_path / "ctrl.fmu"
    assert fmu in written
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    m = result.y.shape[1]
    assert md.fmiVersion == f"{version}.0" and md.coSimulation.modelIdentifier == "ctrl"
    assert [v.name for v in md.modelVariables if v.causality == "input"] == [f"y[{i + 1}]" for i in range(m)] + [
        f"g[{i + 1}]" for i in range(m)
    ]
    if version == 3:
        assert all(v.type == "Float64" for v in md.modelVariables)
        assert [v.name for v in md.modelVariables if v.causality == "independent"] == ["time"]
        assert [f for c in md.buildConfigurations for s in c.sourceFileSets for f in s.sourceFiles] == [
            "ctrl_fmu.c",
            "ctrl_controller.c",
        ]
    names = set(zipfile.ZipFile(fmu).namelist())
    assert {"sources/ctrl_controller.c", "sources/ctrl_fmu.c", *LAYOUT[version]} <= names
    assert version == 2 or not any(n.startswith("sources/fmi") for n in names)

    sim = _fmu_run(fmu, result, T)
    k = len(result.t)
    assert len(sim) == k and np.allclose(sim["time"], result.t, rtol=0, atol=1e-9 * t_end)
    # The Controller fed the same samples: step k returns u_f(k), which the FMU reports at t_k.
    ctrl = quell.Controller(scenario.design(), sample_time=T)
    u_f = np.empty((k, m))
    u = np.empty((k, m))
    for j in range(k):
        u_f[j] = ctrl.step(result.y[j], result.g[j])
        u[j] = ctrl.command()
    fmu_u_f = np.column_stack([sim[f"u_f[{i + 1}]"] for i in range(m)])
    fmu_u = np.column_stack([sim[f"u[{i + 1}]"] for i in range(m)])
    _close(fmu_u_f, u_f)
    _close(fmu_u, u)
    # ... and the sampled loop's own record of the adaptive command u(k) (25).
    _close(fmu_u, result.u)
    assert np.max(np.abs(u_f)) > 0.1  # the controller acted: the comparison is not of zeros


@pytest.mark.parametrize("version", [2, 3])
def test_a_float_fmu_steps_at_a_sample_time_float_cannot_hold(tmp_path, version):
    """T_s = 0.05 is not a float: the f32 FMU held T_s as 0.05f, so a master stepping at 0.05 was
    refused at every step ("h = 0.05 s is not a whole number of samples of T_s = 0.05 s"). T_s is a
    double in every build; the float controller follows the double one to float accuracy."""
    T = 0.05
    scenario, result = _closed_loop(EXAMPLES / "three-channel.toml", T, 5.0)
    quell.export(scenario, T, out=tmp_path, fmu=True, fmi_version=version, prefix="ctrl", precision="f32")
    sim = _fmu_run(tmp_path / "ctrl.fmu", result, T)
    m = result.y.shape[1]
    fmu_u_f = np.column_stack([sim[f"u_f[{i + 1}]"] for i in range(m)])
    assert len(sim) == len(result.t)
    ctrl = quell.Controller(scenario.design(), sample_time=T)
    u_f = np.array([ctrl.step(y, g) for y, g in zip(result.y, result.g)])
    # float's 6e-8 relative rounding, grown over 100 steps of a stable loop: within 1e-3 of the peak.
    np.testing.assert_allclose(fmu_u_f, u_f, rtol=0, atol=1e-3 * np.max(np.abs(u_f)))
    assert np.max(np.abs(u_f)) > 0.1


@pytest.mark.parametrize("version", [2, 3])
def test_communication_step_must_be_whole_samples(tmp_path, capsys, version):
    """A master stepping at 1.5 T_s gets fmiXError from fmiXDoStep, which FMPy raises, and the
    FMU's log (which FMPy's default logger prints) says why."""
    scenario = quell.Scenario.load(EXAMPLES / "three-channel.toml")
    quell.export(scenario, 0.05, out=tmp_path, fmu=True, fmi_version=version)
    with pytest.raises(Exception, match=f"fmi{version}DoStep"):
        simulate_fmu(str(tmp_path / "quell.fmu"), stop_time=1.0, step_size=0.075, output_interval=0.075)
    logged = capsys.readouterr().out
    why = f"fmi{version}DoStep: communication step h = 0.075 s is not a whole number of samples of T_s = 0.05 s"
    assert why in logged, logged


@pytest.mark.parametrize("unit, symbol, factor", [("ms", "ms", 1e-3), ("s", "s", 1.0), ("h", "h", 3600.0), ("µs", "us", 1e-6)])
def test_fmi3_time_is_declared_in_the_plants_unit(tmp_path, unit, symbol, factor):
    """FMI 3.0's independent variable carries the plant model's unit of time, defined as a multiple
    of the SI second (FMPy validates the unit definitions and reads them back)."""
    text = (EXAMPLES / "three-channel.toml").read_text().replace("[plant]\n", f'[plant]\ntime_unit = "{unit}"\n', 1)
    path = tmp_path / "three-channel.toml"
    path.write_text(text)
    assert quell.Scenario.load(path).plant.time_unit == unit
    quell.export(quell.Scenario.load(path), 0.05, out=tmp_path, fmu=True, fmi_version=3, compiler="none")
    fmu = str(tmp_path / "quell.fmu")
    assert validate_fmu(fmu) == []
    md = read_model_description(fmu)
    (time,) = [v for v in md.modelVariables if v.causality == "independent"]
    assert time.name == "time" and time.declaredType is None and time.unit == symbol
    (declared,) = md.unitDefinitions
    assert declared.name == symbol and declared.baseUnit.s == 1 and declared.baseUnit.factor == factor


@pytest.mark.parametrize("unit, version, warned", [("ms", 2, "1000× too slow"), ("min", 2, "60× too fast"),
                                                    ("ms", 3, None), ("s", 2, None)])
def test_fmi2_of_a_plant_not_in_seconds_is_cautioned(tmp_path, unit, version, warned):
    """FMI 2.0 has no unit of time (importers count seconds): an FMU of a plant in ms or min is
    cautioned with the factor a master stepping at the sample time in seconds gets wrong (a maglev
    in ms had been exported without a word); FMI 3.0 declares the unit, and seconds need nothing."""
    import warnings
    text = (EXAMPLES / "three-channel.toml").read_text().replace("[plant]\n", f'[plant]\ntime_unit = "{unit}"\n', 1)
    path = tmp_path / "plant.toml"
    path.write_text(text)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        quell.export(quell.Scenario.load(path), 0.05, out=tmp_path, fmu=True, fmi_version=version, compiler="none")
    texts = [str(w.message) for w in caught if "FMI 2.0 has no unit of time" in str(w.message)]
    if warned is None:
        assert texts == []
    else:
        assert len(texts) == 1 and warned in texts[0] and "(fmi_version)" in texts[0], texts


@pytest.mark.parametrize("version", [2, 3])
def test_variable_descriptions_name_the_plants_signals(tmp_path, version):
    """The plant's `outputs` and `inputs` names go into the variables' descriptions (y_i, g_i and u_i
    the output i, u_f,i the input i), escaped for XML; the variable names stay y[i], u_f[i], …"""
    outputs, inputs = ['level <1> & "A"', "temp"], ["valve", "heater"]
    text = (EXAMPLES / "paper-sampled.toml").read_text()
    quoted = lambda names: "[" + ", ".join('"' + n.replace('"', '\\"') + '"' for n in names) + "]"  # noqa: E731
    text = text.replace("[plant]\n", f"[plant]\noutputs = {quoted(outputs)}\ninputs = {quoted(inputs)}\n", 1)
    scenario = quell.Scenario.from_toml(text)
    quell.export(scenario, 1e-3, out=tmp_path, fmu=True, fmi_version=version, compiler="none")
    fmu = str(tmp_path / "quell.fmu")
    assert validate_fmu(fmu) == []
    described = {v.name: v.description for v in read_model_description(fmu).modelVariables}
    for i in range(2):
        for var, name in (("y", outputs[i]), ("g", outputs[i]), ("u", outputs[i]), ("u_f", inputs[i])):
            assert described[f"{var}[{i + 1}]"].startswith(f"{name}: "), (var, i, described[f"{var}[{i + 1}]"])
    # Without names the descriptions are the symbols' alone.
    quell.export(quell.Scenario.load(EXAMPLES / "paper-sampled.toml"), 1e-3, out=tmp_path / "plain", fmu=True,
                 fmi_version=version, compiler="none")
    plain = read_model_description(str(tmp_path / "plain" / "quell.fmu"))
    assert {v.name: v.description for v in plain.modelVariables}["y[1]"].startswith("measured output y_i")


@pytest.mark.parametrize("version", [2, 3])
def test_source_only_fmu(tmp_path, version):
    scenario = quell.Scenario.load(EXAMPLES / "three-channel.toml")
    written = quell.export(scenario, 0.05, out=tmp_path, fmu=True, fmi_version=version, compiler="none")
    fmu = str(tmp_path / "quell.fmu")
    assert validate_fmu(fmu) == []
    assert not any(n.startswith("binaries/") for n in zipfile.ZipFile(fmu).namelist())
    # The files get the mode a file Python creates gets (the umask applied), not a temporary
    # file's 0600, and no temporary file is left.
    created = tmp_path / "created"
    created.touch()
    mode = lambda p: p.stat().st_mode & 0o777  # noqa: E731
    assert [mode(p) for p in written] == [mode(created)] * 3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["created", "quell.fmu", "quell_controller.c", "quell_controller.h"]
    # The C alone at another sample time keeps that FMU (it may be the user's still) and warns
    # that it was not rewritten (it had stood beside code it no longer matched without a word).
    before = (tmp_path / "quell.fmu").read_bytes()
    with pytest.warns(UserWarning, match=r"^out: quell.fmu beside this code is an earlier export's, not rewritten: .*\(pass fmu=True to write it with this code\)"):
        quell.export(scenario, 0.1, out=tmp_path)
    assert (tmp_path / "quell.fmu").read_bytes() == before


def test_bad_arguments(tmp_path):
    scenario = quell.Scenario.load(EXAMPLES / "three-channel.toml")
    with pytest.raises(quell.ExportError, match=r'^fmi_version: expected 2 or 3, found "4"$'):
        quell.export(scenario, 0.05, out=tmp_path, fmu=True, fmi_version=4)
    with pytest.raises(TypeError, match=r"^fmi_version: expected 2 or 3 \(an int\), found a str$"):
        quell.export(scenario, 0.05, out=tmp_path, fmu=True, fmi_version="3")
    # As the CLI refuses --fmi-version and --compiler without --fmu: an FMU option alone writes no FMU.
    for option in (dict(fmi_version=3), dict(compiler="gcc")):
        name = next(iter(option))
        with pytest.raises(quell.ExportError, match=rf"^{name}: applies to the FMU only; pass fmu=True as well"):
            quell.export(scenario, 0.05, out=tmp_path / "none", **option)
    assert not (tmp_path / "none").exists()
    with pytest.raises(quell.ExportError, match=r"^prefix: expected a C identifier.*found \"9lives\""):
        quell.export(scenario, 0.05, out=tmp_path, prefix="9lives")
    with pytest.raises(quell.ExportError, match=r"^precision: expected f64 or f32, found \"f16\""):
        quell.export(scenario, 0.05, out=tmp_path, precision="f16")
    with pytest.raises(TypeError, match="precision: expected"):
        quell.export(scenario, 0.05, out=tmp_path, precision=64)
    with pytest.raises(TypeError, match="source: expected a quell.Scenario or quell.Design, found a str"):
        quell.export("three-channel.toml", 0.05, out=tmp_path)
    with pytest.raises(quell.ScenarioError, match=r"^sample_time: channel 1's delay"):
        quell.export(scenario.design(), 0.3, out=tmp_path)
    with pytest.raises(quell.ExportError, match=r"^compiler \"/nonexistent/cc\": cannot run it"):
        quell.export(scenario, 0.05, out=tmp_path, fmu=True, compiler="/nonexistent/cc")


@pytest.mark.parametrize("T", [0.05, 0.1, 0.2])
def test_fmi3_time_is_the_decimal_sample_time(tmp_path, T):
    """fmi3GetFloat64 of `time` after k samples is the double nearest the decimal k·T_s, as the
    library's sample times (k * 0.1 gave 0.30000000000000004, 0.6000000000000001, …)."""
    from decimal import Decimal

    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave

    scenario = quell.Scenario.load(EXAMPLES / "paper.toml")
    quell.export(scenario, T, out=tmp_path, fmu=True, fmi_version=3, prefix="ctrl")
    md = read_model_description(str(tmp_path / "ctrl.fmu"))
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(tmp_path / "ctrl.fmu")), modelIdentifier="ctrl", instanceName="t")
    fmu.instantiate()
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    decimal = lambda k: float(Decimal(repr(T)) * k)  # noqa: E731  (Python's float() rounds correctly)
    times = []
    for k in range(300):
        fmu.doStep(decimal(k), T)
        times.append(fmu.getFloat64([8])[0])
    fmu.terminate()
    fmu.freeInstance()
    assert times == [decimal(k + 1) for k in range(300)]


def test_fmi3_calls_one_by_one(tmp_path):
    """FMPy's FMI 3.0 master driven call by call (its FMU3Slave), for what a whole simulation does
    not reach: the independent variable `time` is the time of the next sample; setting it, an
    output or a NaN input, or giving fewer values than value references, is fmi3Error with a
    logged reason that leaves the FMU as it was; eventModeUsed is refused at instantiation."""
    from fmpy import extract
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi3 import FMU3Slave

    scenario = quell.Scenario.load(EXAMPLES / "three-channel.toml")
    quell.export(scenario, 0.05, out=tmp_path, fmu=True, fmi_version=3, prefix="ctrl")
    md = read_model_description(str(tmp_path / "ctrl.fmu"))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    assert vr["time"] == 12 and vr["y[1]"] == 0 and vr["u_f[1]"] == 6  # 4m, then as in FMI 2.0 (m = 3)
    unzipped = extract(str(tmp_path / "ctrl.fmu"))
    logged = []

    def slave():
        return FMU3Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier="ctrl", instanceName="c")

    fmu = slave()
    fmu.instantiate(logMessage=lambda env, status, category, message: logged.append(message.decode()))
    # A step outside step mode (before initialization, after terminate) was accepted and stepped.
    not_stepping = "fmi3DoStep: the FMU is not in step mode; call it between ExitInitializationMode and Terminate"
    with pytest.raises(FMICallException, match="status 3"):
        fmu.doStep(0.0, 0.05)
    assert logged[-1].startswith(not_stepping), logged[-1]
    fmu.enterInitializationMode(startTime=1.0)
    fmu.exitInitializationMode()
    assert fmu.getFloat64([vr["time"]]) == [1.0]
    fmu.setFloat64([vr["y[1]"], vr["g[1]"]], [0.5, 2.0])
    fmu.doStep(1.0, 0.1)  # two samples
    assert fmu.getFloat64([vr["time"], vr["y[1]"], vr["g[1]"]]) == [1.1, 0.5, 2.0]
    refusals = [
        (lambda: fmu.setFloat64([vr["time"]], [0.0]), "fmi3SetFloat64: value reference 12 is not an input (y and g are 0 to 5)"),
        (lambda: fmu.setFloat64([vr["u_f[1]"]], [0.0]), "fmi3SetFloat64: value reference 6 is not an input"),
        (lambda: fmu.setFloat64([vr["y[2]"]], [float("nan")]), "fmi3SetFloat64: input y[2] (value reference 1) is nan; y and g must be finite"),
        (lambda: fmu.getFloat64([vr["y[1]"], vr["y[2]"]], nValues=1), "fmi3GetFloat64: 1 values for 2 value references"),
        (lambda: fmu.getFloat64([13]), "fmi3GetFloat64: no variable has value reference 13 (0 to 11)"),
        (lambda: fmu.doStep(1.0, 0.05), "fmi3DoStep: at t = 1 s, but the controller's next sample is at 1.1 s"),
        # A NaN time passed the test |t − now| > tol (false for NaN) and stepped the controller.
        (lambda: fmu.doStep(float("nan"), 0.1), "fmi3DoStep: at t = nan s, but the controller's next sample is at 1.1 s"),
        # A finite input beyond the controller's bound is refused by the step, which names it.
        (lambda: fmu.setFloat64([vr["g[3]"]], [1e101]) or fmu.doStep(1.1, 0.05),
         "fmi3DoStep: input g[3] = 1e+101 is NaN or beyond +-1e+100; the step was refused"),
        # Just beyond the bound: the value as it reads back, not as %g rounded it (to the bound).
        (lambda: fmu.setFloat64([vr["g[3]"]], [1.0000001e100]) or fmu.doStep(1.1, 0.05),
         "fmi3DoStep: input g[3] = 1.0000001e+100 is NaN or beyond +-1e+100; the step was refused"),
    ]
    for call, why in refusals:
        with pytest.raises(FMICallException, match="status 3"):
            call()
        assert logged[-1].startswith(why), (logged[-1], why)
    assert fmu.getFloat64([vr["time"], vr["y[2]"]]) == [1.1, 0.0]  # nothing was set or stepped
    fmu.terminate()
    with pytest.raises(FMICallException, match="status 3"):
        fmu.doStep(1.1, 0.05)
    assert logged[-1].startswith(not_stepping), logged[-1]
    assert fmu.getFloat64([vr["time"]]) == [1.1]
    # FMI 3.0: a defined stopTime may not be passed (the FMU had stepped on to t = 2 past 1), and a
    # start time whose doubles are coarser than a thousandth of T_s is refused (at 1e17 the
    # samples' times stood still).
    fmu.reset()
    with pytest.raises(FMICallException, match="status 3"):
        fmu.enterInitializationMode(startTime=1e17)
    assert logged[-1].startswith("fmi3EnterInitializationMode: startTime = 1e+17 s: doubles there are 16 s apart"), logged[-1]
    fmu.enterInitializationMode(startTime=0.0, stopTime=1.0)
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 1.0)
    with pytest.raises(FMICallException, match="status 3"):
        fmu.doStep(1.0, 0.05)
    assert logged[-1].startswith("fmi3DoStep: the step to t + h = 1.05 s passes stopTime = 1 s"), logged[-1]
    fmu.freeInstance()

    events = slave()
    with pytest.raises(Exception, match="Failed to instantiate"):
        events.instantiate(eventModeUsed=True, logMessage=lambda env, s, c, message: logged.append(message.decode()))
    assert "this FMU has no event mode (hasEventMode is false)" in logged[-1]


def test_ctrl_c_during_the_fmu_build_stops_the_compiler(tmp_path, python_child):
    """SIGINT while the FMU's compiler runs raises KeyboardInterrupt at once and stops the compiler
    with the processes it started, leaving no temporary directory (it had run to its end; hostile
    review, 2026-12-06)."""
    import os
    import signal
    import time

    pid_file, compiler, temporary = tmp_path / "cc.pid", tmp_path / "slow-cc", tmp_path / "tmp"
    temporary.mkdir()
    compiler.write_text(f"#!/bin/sh\nsleep 60 &\necho $! > {pid_file}\nwait\n")
    compiler.chmod(0o755)
    code = (
        f"import os\nos.environ['TMPDIR'] = {str(temporary)!r}\nimport quell\nprint('ready', flush=True)\n"
        f"try:\n    quell.export(quell.paper_example(), 0.05, out={str(tmp_path / 'out')!r}, fmu=True, compiler={str(compiler)!r})\n"
        "except KeyboardInterrupt:\n    print('interrupted', flush=True)\n"
    )
    child = python_child(code)
    start = time.monotonic()
    while not (pid_file.exists() and pid_file.read_text().strip()):
        assert time.monotonic() - start < 30, "the compiler never started"
        time.sleep(0.02)
    os.kill(child.pid, signal.SIGINT)
    out, err = child.communicate(timeout=30)
    assert out.strip() == "interrupted", out + err
    pid = int(pid_file.read_text())
    start = time.monotonic()
    while time.monotonic() - start < 5:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.02)
    else:
        pytest.fail(f"the compiler's child {pid} still runs")
    assert list(temporary.iterdir()) == []
    assert not (tmp_path / "out" / "quell.fmu").exists()
