"""Output of a comparison: error sentences, the error figure and ``springfem compare``.

:func:`cmd_compare` is the command: it prints the table of
:func:`studies.compare.compare_scene` and writes CSV, Markdown, a PNG of the deformed meshes
coloured by their error and one ``result.json`` + VTU per model.

Examples
--------
>>> import pandas as pd
>>> print(printable(pd.DataFrame({"model": ["spring", "P1"], "converged": [True, False]})))
model     spring  P1
converged    yes  no
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from springfem.scene import Scene

from . import metrics
from .compare import Comparison


def percent(x: float) -> str:
    """A relative error as a percentage, with enough digits to show errors near round-off.

    Parameters
    ----------
    x
        The relative error.

    Returns
    -------
    str
        ``12.34%`` down to 0.01%, scientific below (``3.2e-10%``).

    Examples
    --------
    >>> percent(0.1234), percent(3.2e-12), percent(0.0)
    ('12.34%', '3.2e-10%', '0%')
    """
    if not np.isfinite(x):
        return "nan"
    if x == 0:
        return "0%"
    return f"{x:.2%}" if abs(x) >= 1e-4 else f"{100 * x:.2g}%"


def summary_lines(cmp: Comparison) -> list[str]:
    """Error sentences: model error (spring vs same-mesh P1), total and discretisation.

    Parameters
    ----------
    cmp
        A comparison from :func:`studies.compare.compare_scene`.

    Returns
    -------
    list of str
        One sentence per error kind that can be computed.
    """
    lines = []
    if not cmp.reference:
        return ["no reference: errors not computed (see the notes)"]
    p1 = cmp.same_mesh_p1
    if "spring" in cmp.solutions and p1 is not None:
        e = cmp.errors("spring", p1)
        lines.append(
            f"model error (spring vs {p1}, same mesh): rel L2 {percent(e['rel_l2'])}, "
            f"rel max {percent(e['rel_max'])}"
        )
    if "spring" in cmp.solutions:
        e = cmp.errors("spring")
        lines.append(
            f"total error (spring vs {cmp.reference}): rel L2 {percent(e['rel_l2'])}, "
            f"rel max {percent(e['rel_max'])}"
        )
    if "spring" in cmp.partial:
        lf = cmp.partial["spring"].result.info.get("load_factor", float("nan"))
        lines.append(
            f"spring: partial, stopped at load factor {lf:.4g} of 1; not ranked against "
            f"{cmp.reference} (a state at a lower load)"
        )
    if p1 is not None and p1 != cmp.reference:
        e = cmp.errors(p1)
        lines.append(
            f"discretisation error ({p1} vs {cmp.reference}): rel L2 {percent(e['rel_l2'])}, "
            f"rel max {percent(e['rel_max'])}"
        )
    return lines


def render_comparison(cmp: Comparison, path: str | Path) -> Path:
    """The deformed meshes side by side, coloured by their error against the reference
    (see :func:`figure_fields` for which solutions are drawn).

    Parameters
    ----------
    cmp
        A comparison.
    path
        The PNG to write.

    Returns
    -------
    Path
        The written PNG.
    """
    names = [n for n in cmp.table["model"] if n in cmp.solutions]
    fields, note = figure_fields({n: cmp.solutions[n].u for n in names}, cmp.reference)
    laws = {n: cmp.solutions[n].result.law for n in fields}
    return error_figure(cmp.scene, fields, cmp.reference, path, laws=laws, note=note)


MAX_DRAWN_ERROR = 0.5  # small-strain solutions further off than this are not drawn


def figure_fields(
    fields: dict[str, np.ndarray], reference: str
) -> tuple[dict[str, np.ndarray], str | None]:
    """The fields worth drawing next to a finite-strain reference (neo-Hookean, P2/P1
    mixed), and a note on the rest.

    Small-strain P1/P2 solutions whose largest nodal error exceeds
    :data:`MAX_DRAWN_ERROR` × the largest reference displacement are left out (their
    displacements can be many times the body's size and would flatten the shared colour
    scale); the table keeps them.

    Parameters
    ----------
    fields
        Model name -> vertex displacements ``(n, 3)``.
    reference
        Name of the reference field.

    Returns
    -------
    tuple
        The fields to draw, and a note naming the omitted ones (``None`` if none).
    """
    if not (reference.endswith("-NH") or reference == "fem-P2-mixed"):
        return dict(fields), None
    ref = fields[reference]
    omitted = [
        n
        for n in ("P1", "P2")
        if n in fields and metrics.relative_max_error(fields[n], ref) > MAX_DRAWN_ERROR
    ]
    kept = {n: u for n, u in fields.items() if n not in omitted}
    if not omitted:
        return kept, None
    return (
        kept,
        f"{', '.join(omitted)} (small strain, > {MAX_DRAWN_ERROR:.0%} off) in the table only",
    )


def error_figure(
    scene: Scene,
    fields: dict[str, np.ndarray],
    reference: str,
    path: str | Path,
    laws: dict[str, str] | None = None,
    note: str | None = None,
) -> Path:
    """Render vertex displacement ``fields`` (name -> ``(n, 3)``) of ``scene`` side by side,
    coloured by their error magnitude against ``fields[reference]``, one colour scale.

    Parameters
    ----------
    scene
        The scene (its mesh is drawn).
    fields
        Model name -> vertex displacements.
    reference
        Name of the reference field.
    path
        The PNG to write.
    laws, note
        Law per model for the labels; a note for the title.

    Returns
    -------
    Path
        The written PNG.
    """
    from .plots import Panel, nice_warp_factor, render_error_panels

    ref_u = np.asarray(fields[reference]).reshape(-1, 3)
    lo, hi = scene.mesh.bounding_box()
    warp = nice_warp_factor(float(np.linalg.norm(ref_u, axis=1).max()), float((hi - lo).max()))
    panels = []
    for name, u in fields.items():
        u = np.asarray(u).reshape(-1, 3)
        if name == reference:
            law = (laws or {}).get(name)
            label = f"{name} ({law}): reference" if law else f"{name}: reference"
        else:
            l2 = metrics.relative_l2_error(u, ref_u)
            mx = metrics.relative_max_error(u, ref_u)
            label = f"{name}: rel L2 error {l2:.2%}, max {mx:.2%}"
        panels.append(Panel(label, u, metrics.nodal_error(u, ref_u)))
    scale = "true scale" if warp == 1.0 else f"displacements ×{warp:g}"
    title = f"{scene.name}: deformed meshes ({scale}), coloured by |u − u_{reference}|"
    title += "; grey: rest shape" + (f"; {note}" if note else "")
    return render_error_panels(scene.mesh, panels, path, warp=warp, title=title)


# -------------------------------------------------------------------------------- CLI


def _format_cell(v: object) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (float, np.floating)):
        return "nan" if not np.isfinite(v) else f"{v:.4g}"
    return str(v)


def printable(df: pd.DataFrame, width: int = 24) -> str:
    """The table transposed (one column per model) as aligned text; cells longer than
    ``width`` are replaced by a footnote mark and listed below.

    Parameters
    ----------
    df
        A comparison table with a ``model`` column.
    width
        Longest cell printed in place.

    Returns
    -------
    str
        The aligned text.
    """
    t = df.set_index("model").T.map(_format_cell)
    notes: list[str] = []
    for col in t.columns:
        for row in t.index:
            text = t.at[row, col]
            if len(text) > width:
                notes.append(f"[{len(notes) + 1}] {text}")
                t.at[row, col] = f"[{len(notes)}]"
    return "\n".join([t.to_string(), *notes])
