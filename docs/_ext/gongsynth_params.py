"""
Sphinx extension: tables of an instrument's parameters built from the code.

The tables are generated at build time from ``dataclasses.fields`` of the
instrument's class (`gongsynth.instruments.instrument_class`: name, default
value and the field metadata ``"doc"``), so they cannot drift from the code.
Usage in an RST page::

    .. gongsynth-parameters::
       :stage: filters

lists GONG's parameters that belong to the filter-chain stage; without
``:stage:`` every parameter is listed, one table per stage; ``:instrument: hmi``
takes another instrument of the family (its stages from `INSTRUMENT_STAGES`).
A parameter that the stages do not mention still appears in the full table
(under "Other"), so adding a field to a dataclass never drops it from the
documentation.
"""
import dataclasses

import astropy.units as u
from docutils import nodes
from docutils.parsers.rst import Directive, directives
from docutils.statemachine import StringList
from sphinx.util.nodes import nested_parse_with_titles

__all__ = ["STAGES", "HMI_STAGES", "INSTRUMENT_STAGES", "parameter_rows", "setup"]

#: Which instrument parameters each pipeline stage uses (a parameter may serve
#: several stages; the full table lists it under the first).
STAGES = {
    "spectra": ("Input spectra", ["line_wavelength", "lande_g"]),
    "filters": ("Filter chain", [
        "prefilter_center", "prefilter_fwhm", "prefilter_form", "lyot_delta_h",
        "lyot_angle_1", "lyot_angle_2", "lyot_angle_3", "michelson_fsr",
        "michelson_angle", "waveplate_rate", "integration_half_width", "quadrature_step",
    ]),
    "optics": ("Scene and optics", [
        "aperture", "plate_scale", "detector_shape", "supersampling", "seeing_fwhm",
        "effective_area",
    ]),
    "camera": ("Camera", [
        "frame_rate", "exposure_time", "waveplate_rate", "lcvr_period",
        "quantum_efficiency", "gain", "read_noise", "dither_start", "dither_step",
        "dither_interval", "dither_cycle", "truncate_bits",
    ]),
    "reduction": ("Reduction", [
        "v0", "lande_g", "line_wavelength", "reference_line_fwhm", "reference_line_depth",
    ]),
}


#: HMI's parameters by stage (`gongsynth.instruments.hmi.HMIInstrument`).
HMI_STAGES = {
    "spectra": ("Line and tuning", ["line_wavelength", "lande_g", "tuning_step"]),
    "filters": ("Filter elements", [
        "nb_fsr", "wb_fsr", "e1_fsr", "e2_fsr", "e3_fsr", "e4_fsr", "e5_fsr", "nb_contrast",
        "wb_contrast", "e1_contrast", "e2_contrast", "e3_contrast", "e4_contrast", "e5_contrast",
        "nontunable_phase", "front_window_center", "front_window_fwhm", "front_window_peak",
        "blocker_center", "blocker_fwhm", "blocker_peak", "integration_half_width", "quadrature_step",
    ]),
    "optics": ("Telescope and detector", [
        "aperture", "plate_scale", "detector_shape", "supersampling", "seeing_fwhm", "psf_radius",
        "effective_area",
    ]),
    "camera": ("Camera and frame schedule", [
        "quantum_efficiency", "gain", "read_noise", "full_well", "adc_bits", "exposure_time",
        "frame_interval", "sequence_cadence", "vector_cycle", "vector_window", "vector_cadence",
    ]),
    "reduction": ("Reduction", [
        "reference_line_depth", "reference_line_fwhm", "lut_velocity_max", "lut_velocity_step",
    ]),
}

#: The stages of each instrument's table (an instrument not listed: every parameter under "Other").
INSTRUMENT_STAGES = {"gong": STAGES, "hmi": HMI_STAGES}


def _format_default(value):
    """A short, exact-enough text for a default value."""
    if isinstance(value, u.Quantity):
        number = f"{float(value.value):.6g}"
        if value.unit == u.dimensionless_unscaled:
            return number
        return f"{number} {value.unit.to_string()}"
    if isinstance(value, str):
        return repr(value)
    return str(value)


def parameter_rows(stage=None, instrument="gong"):
    """
    Rows (name, default, description, stage title) of the parameter table.

    Parameters
    ----------
    stage : str, optional
        A key of the instrument's stages (`STAGES` for GONG); ``None`` for every parameter.
    instrument : str
        A registered instrument (`gongsynth.instruments.names`).

    Returns
    -------
    list of tuple of str
    """
    from gongsynth.instruments import instrument_class

    cls = instrument_class(instrument)
    stages = INSTRUMENT_STAGES.get(instrument, {})
    fields = {f.name: f for f in dataclasses.fields(cls)}
    default = cls()
    if stage is not None:
        if stage not in stages:
            raise ValueError(f"unknown stage {stage!r}; expected one of {sorted(stages)}")
        title, names = stages[stage]
        unknown = [n for n in names if n not in fields]
        if unknown:
            raise ValueError(f"STAGES[{stage!r}] names unknown parameter(s) {unknown}")
        order = [(n, title) for n in names]
    else:
        seen, order = set(), []
        for title, names in stages.values():
            for n in names:
                if n in fields and n not in seen:
                    seen.add(n)
                    order.append((n, title))
        order += [(n, "Other") for n in fields if n not in seen]
    return [(n, _format_default(getattr(default, n)), fields[n].metadata.get("doc", ""), title)
            for n, title in order]


class ParameterTable(Directive):
    """The ``gongsynth-parameters`` directive."""

    has_content = False
    option_spec = {"stage": directives.unchanged, "instrument": directives.unchanged}

    def run(self):
        stage = self.options.get("stage")
        instrument = self.options.get("instrument", "gong")
        try:
            rows = parameter_rows(stage, instrument)
        except ValueError as exc:
            raise self.error(str(exc)) from exc
        lines = []
        if stage is not None:
            lines += _table(rows)
        else:  # every parameter: one table per stage, in STAGES order, "Other" last
            titles = list(dict.fromkeys(title for *_, title in rows))
            for title in titles:
                lines += [f".. rubric:: {title}", ""]
                lines += _table([row for row in rows if row[3] == title]) + [""]
        # Re-read this page whenever the instrument's source changes.
        import inspect

        from gongsynth.instruments import instrument_class
        self.state.document.settings.env.note_dependency(inspect.getsourcefile(instrument_class(instrument)))
        container = nodes.container()
        nested_parse_with_titles(self.state, StringList(lines, source="gongsynth-parameters"),
                                 container)
        return container.children


def _table(rows):
    """RST list-table lines for ``rows`` of `parameter_rows`."""
    lines = [".. list-table::", "   :header-rows: 1", "   :widths: 34 18 48",
             "   :class: gongsynth-parameters", "",
             "   * - Parameter", "     - Default", "     - Meaning and source"]
    for name, value, doc, _ in rows:
        lines += [f"   * - ``{name}``", f"     - ``{value}``", f"     - {doc}"]
    return lines


def setup(app):
    app.add_directive("gongsynth-parameters", ParameterTable)
    return {"version": "1.0", "parallel_read_safe": True, "parallel_write_safe": True}
