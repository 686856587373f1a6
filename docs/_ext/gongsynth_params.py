"""
Sphinx extension: tables of `gongsynth.GONGInstrument` parameters built from the code.

The tables are generated at build time from ``dataclasses.fields(GONGInstrument)``
(name, default value and the field metadata ``"doc"``), so they cannot drift
from the code.  Usage in an RST page::

    .. gongsynth-parameters::
       :stage: filters

lists the parameters that belong to the filter-chain stage; without ``:stage:``
every parameter is listed, one table per stage.  A parameter that ``STAGES`` does
not mention still appears in the full table (under "Other"), so adding a field
to the dataclass never drops it from the documentation.
"""
import dataclasses

import astropy.units as u
from docutils import nodes
from docutils.parsers.rst import Directive, directives
from docutils.statemachine import StringList
from sphinx.util.nodes import nested_parse_with_titles

__all__ = ["STAGES", "parameter_rows", "setup"]

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


def parameter_rows(stage=None):
    """
    Rows (name, default, description, stage title) of the parameter table.

    Parameters
    ----------
    stage : str, optional
        A key of `STAGES`; ``None`` for every parameter.

    Returns
    -------
    list of tuple of str
    """
    from gongsynth import GONGInstrument

    fields = {f.name: f for f in dataclasses.fields(GONGInstrument)}
    default = GONGInstrument()
    if stage is not None:
        if stage not in STAGES:
            raise ValueError(f"unknown stage {stage!r}; expected one of {sorted(STAGES)}")
        title, names = STAGES[stage]
        unknown = [n for n in names if n not in fields]
        if unknown:
            raise ValueError(f"STAGES[{stage!r}] names unknown parameter(s) {unknown}")
        order = [(n, title) for n in names]
    else:
        seen, order = set(), []
        for title, names in STAGES.values():
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
    option_spec = {"stage": directives.unchanged}

    def run(self):
        stage = self.options.get("stage")
        try:
            rows = parameter_rows(stage)
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

        from gongsynth import instrument
        self.state.document.settings.env.note_dependency(inspect.getsourcefile(instrument))
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
