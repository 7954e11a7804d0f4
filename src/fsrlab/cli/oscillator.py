"""``fsrlab oscillator``, ``fsrlab decode``, ``fsrlab design``: the LM555 readout (paper §5)."""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager

import typer

from fsrlab.cli import app
from fsrlab.cli.options import emit_json, fail, farads, fraction, hertz, ohms, option_names, seconds, volts
from fsrlab.hardware import CAPTURE_MAX_HZ
from fsrlab.units import format_eng

_NAMES = {"control_v": "--vctrl", "discharge_ohm": "--rdis", "r_ohm": "--r", "r_fsr_ohm": "--rfsr",
          "c_fsr_farad": "--cfsr", "c_off_farad": "--coff",
          "diode_drop_v": "--diode-drop", "vcc_v": "--vcc", "frequency_hz": "--frequency",
          "duty_cycle": "--duty", "periods": "--periods", "r_fsr_range_ohm": "--rfsr-min/--rfsr-max",
          "c_fsr_range_farad": "--cfsr-min/--cfsr-max", "band_hz": "--fmin/--fmax", "variant": "--variant",
          "min_margin": "--margin", "window_s": "--window", "max_frequency_hz": "--max-frequency"}


def _variant(diode: bool, diode_drop: float | None) -> tuple[bool, float]:
    if diode_drop is None:
        return diode, 0.0
    if not (math.isfinite(diode_drop) and diode_drop >= 0):
        fail(f"must be a forward drop >= 0 V, got {diode_drop:g}", "--diode-drop")
    return True, diode_drop


def _circuit(r: float, coff: float, diode: bool, drop: float, vcc: float, vctrl: float | None, rdis: float):
    """The LM555Circuit the options describe (call inside ``option_names(_NAMES)``)."""
    from fsrlab.circuits.circuit import LM555Circuit

    parts = dict(r_ohm=r, c_off_farad=coff, diode=diode, diode_drop_v=drop, vcc_v=vcc, discharge_ohm=rdis)
    return LM555Circuit(**parts) if vctrl is None else LM555Circuit.with_control(vctrl, **parts)


# The options to blame for each way a circuit can fail to oscillate (NoOscillationError.condition).
_NO_OSCILLATION = {"charge": "--r/--rfsr", "diode_drop": "--diode-drop", "discharge": "--rdis"}


@contextmanager
def _model_errors(diode: bool = False) -> Iterator[None]:
    """Model errors as one line naming the options; numpy's overflow warnings silenced (results are checked)."""
    import numpy as np

    from fsrlab.circuits.lm555 import NoOscillationError

    with option_names(_NAMES), np.errstate(all="ignore"):
        try:
            yield
        except NoOscillationError as exc:
            blame = "--rfsr" if exc.condition == "discharge" and diode else _NO_OSCILLATION.get(exc.condition)
            fail(exc.reason, blame)


_LABELS = {"frequency_hz": "f", "duty_cycle": "duty cycle", "tau_high_s": "τH", "tau_low_s": "τL", "n_ratio": "N",
           "sensitivity_c": "∂ln f/∂ln C_FSR", "sensitivity_r": "∂ln f/∂ln R_FSR", "r_fsr_ohm": "R_FSR",
           "c_fsr_farad": "C_FSR", "r_fsr_std_ohm": "σ(R_FSR)", "c_fsr_std_farad": "σ(C_FSR)"}


def _finite(values: dict, what: str, options: str) -> None:
    """Fail naming ``options`` when a result is not a finite number (parts beyond floating point)."""
    bad = {k: v for k, v in values.items() if not math.isfinite(v)}
    if bad:
        shown = ", ".join(f"{_LABELS.get(k, k)} = {v:g}" for k, v in bad.items())
        fail(f"no finite {what} for these values ({shown}): they leave the range of floating point", options)


def _diode_text(diode: bool, drop: float) -> str:
    if not diode:
        return "no diode"
    return f"D1 with {drop:g} V drop" if drop > 0 else "ideal D1"


@app.command("oscillator")
def oscillator(
    r: float = typer.Option(..., "--r", parser=ohms, help="R_A = R_B = R [Ω], e.g. 10k."),
    rfsr: float = typer.Option(..., "--rfsr", parser=ohms, help="FSR resistance R_FSR [Ω], e.g. 200k."),
    cfsr: float = typer.Option(..., "--cfsr", parser=farads, help="FSR capacitance C_FSR [F], e.g. 1n."),
    coff: float = typer.Option(0.0, "--coff", parser=farads, help="Offset capacitor C_off in parallel [F], e.g. 470p."),
    diode: bool = typer.Option(False, "--diode", help="Ideal diode D1 in series with R_B (paper Fig. 13)."),
    diode_drop: float = typer.Option(None, "--diode-drop", parser=volts, help="D1 with this forward drop [V], e.g. 0.6 "
            "(implies --diode)."),
    vcc: float = typer.Option(5.0, "--vcc", parser=volts, help="Supply [V]."),
    vctrl: float = typer.Option(None, "--vctrl", parser=volts, help="Control-pin voltage [V] (thresholds at Vctrl and "
            "Vctrl/2; default: open pin, 2/3·Vcc)."),
    rdis: float = typer.Option(0.0, "--rdis", parser=ohms, help="Discharge-transistor on-resistance [Ω] (default 0: "
            "ideal, as in the paper)."),
    spice: bool = typer.Option(False, "--spice", help="Also simulate the circuit in ngspice and show its frequency and "
            "duty cycle."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Frequency, duty cycle and sensitivities of the LM555 astable with the FSR as timing element.

    Examples (the paper's circuit with D1; a 4.7 kΩ circuit with 1 nF of C_off at 3.3 V, as JSON):

    \b
      fsrlab oscillator --r 10k --rfsr 200k --cfsr 1n --diode
      fsrlab oscillator --r 4k7 --rfsr 1meg --cfsr 470pF --coff 1n --vcc 3.3V --json
    """
    import subprocess

    from fsrlab.circuits.lm555 import minimum_n_ratio

    diode, drop = _variant(diode, diode_drop)
    with _model_errors(diode):
        circuit = _circuit(r, coff, diode, drop, vcc, vctrl, rdis)
        res = circuit.astable(rfsr, cfsr, check=False)
        if not res.oscillates:
            circuit.astable(rfsr, cfsr)  # raises NoOscillationError saying which condition failed
        sens = circuit.sensitivity(rfsr, cfsr)
    out = {"frequency_hz": float(res.frequency_hz), "duty_cycle": float(res.duty_cycle),
           "tau_high_s": float(res.tau_high_s), "tau_low_s": float(res.tau_low_s), "n_ratio": float(res.n_ratio),
           "sensitivity_c": float(sens.c_fsr), "sensitivity_r": float(sens.r_fsr)}
    _finite(out, "frequency, duty cycle and sensitivities", "--r/--rfsr/--cfsr/--coff")
    if spice:
        from fsrlab.circuits.spice import ngspice_available

        if not ngspice_available():
            fail("ngspice is not installed (`make sysdeps` installs it)", "--spice")
        try:
            with option_names(_NAMES):
                sim = circuit.simulate_spice(rfsr, cfsr, periods=20, timeout_s=120.0)
        except (RuntimeError, subprocess.TimeoutExpired) as exc:  # the simulator, not the input: exit 1
            typer.echo(f"fsrlab: --spice: {' '.join(str(exc).split())}", err=True)
            raise typer.Exit(1) from None
        out["spice_frequency_hz"] = sim.frequency_hz
        out["spice_duty_cycle"] = sim.duty_cycle
    if json_out:
        emit_json(out)
        return
    n_min = minimum_n_ratio(circuit.diode_drop_v, circuit.vcc_v, circuit.upper_fraction)
    lines = [
        f"LM555 astable: R = {format_eng(r, 'Ω')}, R_FSR = {format_eng(rfsr, 'Ω')}, C_FSR = {format_eng(cfsr, 'F')}, "
        f"C_off = {format_eng(coff, 'F')}, {_diode_text(diode, drop)}, Vcc = {vcc:g} V",
        f"  frequency        {format_eng(out['frequency_hz'], 'Hz', 5)}",
        f"  duty cycle       {100 * out['duty_cycle']:.4g} %",
        f"  τH (output high) {format_eng(out['tau_high_s'], 's')}",
        f"  τL (output low)  {format_eng(out['tau_low_s'], 's')}",
        f"  N = R_FSR/R      {out['n_ratio']:.4g} (oscillates for N > {n_min:.4g}; margin "
        f"{100 * (out['n_ratio'] / n_min - 1):.3g} %)",
        f"  ∂ln f/∂ln C_FSR  {out['sensitivity_c']:+.4f}",
        f"  ∂ln f/∂ln R_FSR  {out['sensitivity_r']:+.4f}",
    ]
    if spice:
        lines.append(f"  ngspice          {format_eng(out['spice_frequency_hz'], 'Hz', 5)}, duty cycle "
                     f"{100 * out['spice_duty_cycle']:.4g} % "
                     f"(Δf {100 * (out['spice_frequency_hz'] / out['frequency_hz'] - 1):+.3g} %)")
    typer.echo("\n".join(lines))


@app.command("decode")
def decode_cmd(
    r: float = typer.Option(..., "--r", parser=ohms, help="R_A = R_B = R of the circuit [Ω], e.g. 10k."),
    frequency: float = typer.Option(..., "--frequency", parser=hertz, help="Measured frequency [Hz], e.g. 6478.5 or "
            "6.4785k."),
    duty: float = typer.Option(..., "--duty", parser=fraction, help="Measured duty cycle, the output-high fraction "
            "[1], e.g. 0.10189 or 10.189%."),
    coff: float = typer.Option(0.0, "--coff", parser=farads, help="Offset capacitor C_off [F], e.g. 470p."),
    diode: bool = typer.Option(False, "--diode", help="The circuit has the ideal diode D1."),
    diode_drop: float = typer.Option(None, "--diode-drop", parser=volts, help="D1 with this forward drop [V] (implies "
            "--diode)."),
    vcc: float = typer.Option(5.0, "--vcc", parser=volts, help="Supply [V]."),
    vctrl: float = typer.Option(None, "--vctrl", parser=volts, help="Control-pin voltage [V] (default: open pin)."),
    rdis: float = typer.Option(0.0, "--rdis", parser=ohms, help="Discharge-transistor on-resistance [Ω] (default 0)."),
    periods: int = typer.Option(1, "--periods", help="Periods averaged into the measurement [1], e.g. 100 (for the "
            "uncertainty)."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Recover R_FSR and C_FSR from a measured frequency and duty cycle (uncertainty: 62.5 ns timer ticks).

    Example (what the oscillator example's circuit gives, averaged over 100 periods):

    \b
      fsrlab decode --r 10k --frequency 6.4785kHz --duty 10.189% --diode --periods 100
    """
    diode, drop = _variant(diode, diode_drop)
    with _model_errors(diode):
        res = _circuit(r, coff, diode, drop, vcc, vctrl, rdis).decode(frequency, duty, periods=periods)
    out = {"r_fsr_ohm": float(res.r_fsr_ohm), "c_fsr_farad": float(res.c_fsr_farad),
           "r_fsr_std_ohm": float(res.r_fsr_std_ohm), "c_fsr_std_farad": float(res.c_fsr_std_farad)}
    _finite(out, "R_FSR and C_FSR", "--r/--frequency/--duty/--coff")
    if json_out:
        emit_json(out)
        return
    typer.echo("\n".join([
        f"Decoded for R = {format_eng(r, 'Ω')}, C_off = {format_eng(coff, 'F')}, {_diode_text(diode, drop)}, "
        f"{periods} period(s) averaged:",
        f"  R_FSR = {format_eng(out['r_fsr_ohm'], 'Ω', 6)} ± {format_eng(out['r_fsr_std_ohm'], 'Ω', 3)}",
        f"  C_FSR = {format_eng(out['c_fsr_farad'], 'F', 6)} ± {format_eng(out['c_fsr_std_farad'], 'F', 3)}",
        "  (± one standard deviation from 62.5 ns timer quantization)",
    ]))


@app.command("design")
def design_cmd(
    rfsr_min: float = typer.Option(..., "--rfsr-min", parser=ohms, help="Smallest R_FSR of the sensor (full load) [Ω], "
            "e.g. 100k."),
    rfsr_max: float = typer.Option(..., "--rfsr-max", parser=ohms, help="Largest R_FSR (no load) [Ω], e.g. 2M."),
    cfsr_min: float = typer.Option(..., "--cfsr-min", parser=farads, help="Smallest C_FSR [F], e.g. 0.5n."),
    cfsr_max: float = typer.Option(..., "--cfsr-max", parser=farads, help="Largest C_FSR [F], e.g. 1.5n."),
    fmin: float = typer.Option(..., "--fmin", parser=hertz, help="Lowest wanted frequency [Hz], e.g. 1k."),
    fmax: float = typer.Option(..., "--fmax", parser=hertz, help="Highest wanted frequency [Hz], e.g. 20k."),
    variant: str = typer.Option("auto", "--variant", help="Circuit variant: auto (the better one), diode or no-diode."),
    diode_drop: float = typer.Option(0.0, "--diode-drop", parser=volts, help="Forward drop of D1 in the diode variant "
            "[V], e.g. 0.6."),
    vcc: float = typer.Option(5.0, "--vcc", parser=volts, help="Supply [V]."),
    margin: float = typer.Option(0.25, "--margin", parser=fraction, help="Required oscillation margin N/N_min − 1 at "
            "the smallest R_FSR [1], e.g. 0.25 or 25%."),
    window: float = typer.Option(0.1, "--window", parser=seconds, help="Measurement window for the stated resolution "
            "[s], e.g. 100ms or 0.1."),
    max_frequency: float = typer.Option(
        CAPTURE_MAX_HZ, "--max-frequency", parser=hertz,
        help=f"Highest frequency the counter captures every edge of [Hz]; the band's top is lowered to it "
             f"(default: the fsrlab meter, {CAPTURE_MAX_HZ / 1e3:g}k, measured in simavr). For another counter, e.g. "
             "2M."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Propose R, C_off and the variant for a sensor's R_FSR/C_FSR ranges and a wanted frequency band.

    Examples (a band the fsrlab meter captures; a 1–2 MHz band for a counter that captures 5 MHz):

    \b
      fsrlab design --rfsr-min 100k --rfsr-max 2M --cfsr-min 0.5n --cfsr-max 1.5n --fmin 1k --fmax 20k
      fsrlab design --rfsr-min 100k --rfsr-max 2M --cfsr-min 0.5n --cfsr-max 1.5n --fmin 1M --fmax 2M --max-frequency 5M
    """
    from dataclasses import asdict

    from fsrlab.circuits.design import design

    if not max_frequency > 0:
        fail(f"must be > 0 Hz, got {max_frequency:g}", "--max-frequency")
    if fmin >= max_frequency:
        meter = max_frequency == CAPTURE_MAX_HZ
        who, why = ("the fsrlab meter", "its firmware's limit, measured in "
                "simavr") if meter else ("the counter", "--max-frequency")
        fail(f"{format_eng(fmin, 'Hz')} … {format_eng(fmax, 'Hz')} is beyond what {who} captures: every edge only up "
             "to "
             f"{format_eng(max_frequency, 'Hz')} ({why}); lower the band, or give --max-frequency for another counter",
             "--fmin/--fmax")
    with _model_errors():
        d = design((rfsr_min, rfsr_max), (cfsr_min, cfsr_max), (fmin, fmax), variant=variant,
                   diode_drop_v=diode_drop if variant != "no-diode" else 0.0, vcc_v=vcc, min_margin=margin,
                   window_s=window, max_frequency_hz=max_frequency)
    if json_out:
        emit_json(asdict(d))
        return
    f0, f1 = d.frequency_range_hz
    b0, b1 = d.band_hz
    capped = f", --fmax {format_eng(fmax, 'Hz')} lowered to what the counter captures" if fmax > b1 else ""
    others = [a for a in d.alternatives if a["diode"] != d.diode]
    lines = [
        f"Proposal: {'with' if d.diode else 'without'} diode D1, R = {format_eng(d.r_ohm, 'Ω')}, "
        f"C_off = {format_eng(d.c_off_farad, 'F')}",
        f"  frequency        {format_eng(f0, 'Hz')} … {format_eng(f1, 'Hz')} "
        f"(band {format_eng(b0, 'Hz')} … {format_eng(b1, 'Hz')}{capped})",
        f"  duty cycle       {100 * d.duty_cycle_range[0]:.3g} … {100 * d.duty_cycle_range[1]:.3g} %",
        f"  oscillation      N/N_min − 1 ≥ {100 * d.margin:.3g} % over the whole range",
        f"  ∂ln f/∂ln C_FSR  {d.sensitivity_c_range[0]:+.3f} … {d.sensitivity_c_range[1]:+.3f}",
        f"  ∂ln f/∂ln R_FSR  {d.sensitivity_r_range[0]:+.3f} … {d.sensitivity_r_range[1]:+.3f}"
        f"  (capacitive share ≥ {100 * d.capacitive_share:.3g} %)",
        f"  Uno resolution   (62.5 ns ticks) one period: {format_eng(d.resolution_single_hz[0], 'Hz')} at "
        f"{format_eng(b0, 'Hz')}, {format_eng(d.resolution_single_hz[1], 'Hz')} at {format_eng(b1, 'Hz')} "
        f"(band ends); {format_eng(d.range_resolution_single_hz[0], 'Hz')} at {format_eng(f0, 'Hz')}, "
        f"{format_eng(d.range_resolution_single_hz[1], 'Hz')} at {format_eng(f1, 'Hz')} (sensor range)",
        f"                   {format_eng(d.window_s, 's')} window: {format_eng(d.resolution_window_hz[0], 'Hz')}, "
        f"{format_eng(d.resolution_window_hz[1], 'Hz')} (band ends); "
        f"{format_eng(d.range_resolution_window_hz[0], 'Hz')}, "
        f"{format_eng(d.range_resolution_window_hz[1], 'Hz')} (sensor range)",
    ]
    for a in others:
        lines.append(f"  other variant    {'with' if a['diode'] else 'without'} D1: R = {format_eng(a['r_ohm'], 'Ω')}, "
                     f"C_off = {format_eng(a['c_off_farad'], 'F')}, ∂ln f/∂ln R_FSR "
                     f"{a['sensitivity_r_range'][0]:+.3f} … {a['sensitivity_r_range'][1]:+.3f}")
    typer.echo("\n".join(lines))
