"""Every output quantity, declared once: name, unit, meaning and which scenes have it.

The :class:`pulloff.solvers.result.Result`, the HDF5 units, the sweep columns, the console table
and the README's output list are all read from :data:`OUTPUTS`. A quantity a scene does not have
is ``nan`` (or empty text) in its result, never missing.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

#: Which scenes have a quantity (the ``where`` of :class:`Quantity`), as a user reads it.
WHERE = {
    "all": "every scene",
    "pull": "scenes pulled at constant speed (loading.kind = constant_velocity)",
    "separation": "scenes run to separation (model.until = separation) or with a receding "
                  "contact edge (internal zone, compliant machine, Maxwell solids)",
    "seed": "the flat punch with its zone outside (the seed's closed forms)",
    "elastic_limit": "solids with a relaxed modulus G_inf > 0",
    "maxwell": "standard linear solids and Prony series (the instantaneous modulus)",
    "path": "scenes with a loading path (loading.kind = path)",
    "jump": "paths where the contact is gained or lost by a jump",
    "sphere": "spheres",
    "elastic_path": "elastic solids on a loading path (a flat punch: its elastic onset "
                    "force, its pull-off on any path)",
    "memory_path": "solids with memory on a loading path: standard linear solids and Prony "
                   "series, and Kelvin-Voigt flat punches (whose instantaneous modulus is "
                   "infinite: relaxed only)",
}


@dataclass(frozen=True)
class Quantity:
    name: str
    unit: str  # SI; "1" dimensionless, "" text or flag
    meaning: str
    group: str  # history | summary | analytic
    where: str = "all"  # a key of WHERE
    text: bool = False  # a string or flag, not a number


def _q(group):
    def make(name, unit, meaning, where="all", text=False):
        return Quantity(name, unit, meaning, group, where, text)
    return make


_h, _s, _a = _q("history"), _q("summary"), _q("analytic")

OUTPUTS = (
    _h("t", "s", "time"),
    _h("h", "m", "indenter lift (negative when pressed in); behind a spring it lags the driver"),
    _h("a", "m", "contact (bond) radius"),
    _h("b", "m", "end of the cohesive zone"),
    _h("gap", "m", "gap between the surfaces at r = b"),
    _h("F_contact", "N", "force on the contact (bonded) region, tension positive"),
    _h("F_total", "N", "force of the whole line load: contact and cohesive zone"),
    _h("segment", "1", "index of the loading segment (0 for a constant-speed pull)"),

    _s("detached", "", "whether the onset of detachment was reached", text=True),
    _s("t_detach", "s", "onset of detachment: first time with gap(b) = delta"),
    _s("h_detach", "m", "lift at the onset"),
    _s("b_detach", "m", "cohesive-zone end at the onset"),
    _s("zone_ratio_detach", "1", "(b - a)/a at the onset"),
    _s("F_contact_detach", "N", "F_contact at the onset (the seed's pull-off force, eq. 48)"),
    _s("F_total_detach", "N", "F_total at the onset"),
    _s("t_separation", "s", "the first complete separation: the zone has vanished", "separation"),
    _s("F_peak_contact", "N", "largest F_contact of the run", "separation"),
    _s("F_peak_total", "N", "largest F_total of the run (the pull-off force)", "separation"),
    _s("t_peak_contact", "s", "time of the largest F_contact (not error-controlled: the time "
                              "of a smooth maximum is ill-conditioned)", "separation"),
    _s("t_peak_total", "s", "time of the largest F_total (not error-controlled, likewise)",
       "separation"),
    _s("F_pulloff", "N", "the most tensile F_total of the path (the pull-off force)", "path"),
    _s("h_pulloff", "m", "lift at F_pulloff (not error-controlled: the place of a smooth "
                         "maximum is ill-conditioned)", "path"),
    _s("t_pulloff", "s", "time of F_pulloff (not error-controlled, likewise)", "path"),
    _s("F_max_compressive", "N", "the most compressive F_total of the path (negative)", "path"),
    _s("F_jump_in", "N", "F_total just before the surface first jumps into contact", "jump"),
    _s("h_jump_in", "m", "lift where the surface first jumps into contact", "jump"),
    _s("F_jump_out", "N", "F_total just before the contact is first lost by a jump", "jump"),
    _s("h_jump_out", "m", "lift where the contact is first lost by a jump", "jump"),
    _s("energy_dissipated", "J", "int F_total dh over the whole path: the machine's net work, "
                                 "the energy lost over a closed cycle", "path"),
    _s("work_separation", "J", "int max(F_total, 0) dh over the last retraction: the work "
                               "to pull the indenter off", "path"),
    _s("maugis_lambda", "1", "Maugis' parameter 2 sigma_c (R / (pi gamma K^2))^(1/3), "
                             "K = 16 G_inf / 3 (the relaxed modulus)", "sphere"),
    _s("speed_relaxation", "1", "the last retraction speed times the longest relaxation "
                                "time, over delta", "path"),
    _s("alpha", "1", "the seed's group pi delta sigma_c a G / (4 v^2 eta^2)", "pull"),
    _s("chi", "1", "elastic zone size pi G delta / (sigma_c a)", "pull"),
    _s("V", "1", "viscous against cohesive stress eta v / (sigma_c a)", "pull"),
    _s("error_estimate", "1", "estimated relative error of the controlled outputs"),
    _s("observed_order", "1", "order of the error in the step, measured from the last three "
                              "levels (nan where they do not support one, and for the "
                              "quadrature onset, which has no steps)"),
    _s("n_elements", "1", "foundation elements of the reported run (quadrature onset: Gauss "
                          "nodes of one gap evaluation at the onset)"),
    _s("n_steps", "1", "time steps of the reported run (quadrature onset: gap evaluations)"),
    _s("wall_time", "s", "wall-clock time of the simulation"),
    _s("t_end", "s", "last simulated time"),
    _s("solver", "", "the solver that ran the scene", text=True),
    _s("history", "", "model.history of the scene", text=True),
    _s("until", "", "model.until of the scene", text=True),
    _s("cohesive_zone", "", "geometry.cohesive_zone of a flat punch", text=True),
    _s("notes", "", "what the user should know about this run, joined by '; '", text=True),

    _a("seed_linearised_t_detach", "s", "root of the seed's eq. 53", "seed"),
    _a("seed_linearised_F", "N", "eq. 48 at the eq. 53 root", "seed"),
    _a("seed_closed_form_t_detach", "s", "the seed's closed-form t (eqs. 64/89)", "seed"),
    _a("seed_closed_form_F", "N", "the seed's closed-form force", "seed"),
    _a("seed_closed_form_branch", "", "which closed form applies (small or large alpha)", "seed",
       text=True),
    _a("kendall_F", "N", "Kendall's pull-off force sqrt(8 pi E* a^3 gamma) (eq. 95)",
       "elastic_limit"),
    _a("viscous_F", "N", "the viscous limit 8 eta v a (eq. 96)", "pull"),
    _a("elastic_F_contact", "N", "elastic MDR-Dugdale F_contact with the relaxed modulus",
       "elastic_limit"),
    _a("elastic_F_total", "N", "elastic MDR-Dugdale F_total with the relaxed modulus",
       "elastic_limit"),
    _a("elastic_b", "m", "elastic MDR-Dugdale zone end with the relaxed modulus",
       "elastic_limit"),
    _a("elastic_instant_F_contact", "N", "elastic F_contact with the instantaneous modulus",
       "maxwell"),
    _a("elastic_instant_F_total", "N", "elastic F_total with the instantaneous modulus",
       "maxwell"),
    _a("mdr_dugdale_F_pulloff_load", "N", "elastic MDR-Dugdale pull-off under load control, "
                                          "from the equilibrium curve of the indenter's own "
                                          "profile (an independent semi-analytic solution)",
       "elastic_path"),
    _a("mdr_dugdale_F_pulloff_displacement", "N", "the same under displacement control (where "
                                                  "a rigid lift leaves the curve; behind a "
                                                  "machine spring, where the driver does)",
       "elastic_path"),
    _a("jkr_F_pulloff_load", "N", "JKR pull-off under load control (the limit of an infinitely "
                                  "strong, short-ranged adhesion)", "elastic_path"),
    _a("maugis_F_pulloff_load", "N", "Maugis-Dugdale pull-off of a sphere, load control",
       "sphere"),
    _a("maugis_F_pulloff_displacement", "N", "Maugis-Dugdale pull-off of a sphere, "
                                             "displacement control by a rigid machine",
       "sphere"),
    _a("relaxed_F_pulloff", "N", "the largest tensile force of the elastic MDR-Dugdale curve "
                                 "with the relaxed modulus G_inf: a slow retraction's limit",
       "memory_path"),
    _a("instant_F_pulloff", "N", "the same with the instantaneous modulus G(0+): a fast "
                                 "retraction's limit", "memory_path"),
)

BY_NAME = {q.name: q for q in OUTPUTS}


@functools.lru_cache(maxsize=None)
def of_group(group: str) -> tuple[Quantity, ...]:
    # (once per group: every result is built from these, ~70 quantities a call)
    return tuple(q for q in OUTPUTS if q.group == group)


@functools.lru_cache(maxsize=None)
def names(group: str) -> tuple[str, ...]:
    """The names of one group, in declaration order."""
    return tuple(q.name for q in of_group(group))


@functools.lru_cache(maxsize=None)
def _missing(group: str) -> dict:
    return {q.name: "" if q.text else math.nan for q in of_group(group)}


def missing(group: str) -> dict:
    """``name -> value`` of a quantity a scene does not have (nan, or empty text), for one
    group in declaration order (a new dict: a result fills in its own values)."""
    return dict(_missing(group))


def units(group: str) -> dict[str, str]:
    """``name -> unit`` of one group, in declaration order."""
    return {q.name: q.unit for q in of_group(group)}


def numeric(group: str) -> tuple[str, ...]:
    return tuple(q.name for q in of_group(group) if not q.text)


def markdown() -> str:
    """The README's list of outputs, generated from the table (a test keeps them equal)."""
    titles = {"history": "`history/` datasets (one time axis, `t` attached as their scale)",
              "summary": "`summary` attributes (each with a `NAME__unit` companion)",
              "analytic": "`analytic` attributes: closed forms beside the run"}
    lines = []
    for group, title in titles.items():
        lines.append(f"- {title}:")
        for q in of_group(group):
            unit = f" [{q.unit}]" if q.unit not in ("", "1") else ""
            where = "" if q.where == "all" else f" ({WHERE[q.where]}; nan otherwise)"
            lines.append(f"  - `{q.name}`{unit}: {q.meaning}{where}")
    return "\n".join(lines)
