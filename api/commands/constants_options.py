"""The timescale constants' options (eq. timescale), written once for every command that
turns tau into seconds: ``dose``, ``schedule``, ``release``, ``fit kinetics``.

Unset options keep :class:`dosing.units.PhysicalConstants`' defaults (Omega_p = Omega Omega_f,
consistent with the gel's Omega); ``--paper-constants`` starts from the paper's instead.
"""

from __future__ import annotations

import argparse
from typing import Any

FIELDS = {"viscosity": "viscosity_pa_s", "polymer_volume_m3": "polymer_volume_m3",
          "k0_m2": "permeability_m2", "mesh_length_nm": "mesh_length_nm",
          "k0_law": "k0_law", "k0_reference_t_k": "k0_reference_t_k"}


def viscosity(text: str) -> float | str:
    """'water', a number in Pa s, or a quantity ('1 mPa s')."""
    if text.strip().lower() == "water":
        return text
    from dosing.quantity import to_unit

    return to_unit(text, "viscosity", "--viscosity")


def add_constants_options(p: Any, *, mesh: bool = True, k0: bool = True) -> None:
    """--viscosity, --polymer-volume-m3, --k0-m2, --mesh-length-nm, --paper-constants."""
    p.add_argument("--viscosity", type=viscosity, default=None,
                   help="fluid viscosity in Pa s, or 'water' for water at T_end (default 1e-3)")
    p.add_argument("--polymer-volume-m3", type=float, default=None,
                   help="Omega_p, volume of a polymer unit in m^3 (default Omega Omega_f, "
                        "consistent with the gel's Omega: 3e-27 m^3 for ANB; the paper's "
                        "3e-25 with --paper-constants)")
    if k0:
        p.add_argument("--k0-m2", type=float, default=None,
                       help="permeability scale k0 in m^2 (default 8e-20)")
        p.add_argument("--k0-law", choices=["constant", "tokita-tanaka"], default=None,
                       help="k0's temperature law, in the envelope only (default constant; "
                            "tokita-tanaka: the friction's fall near the transition, Tokita "
                            "& Tanaka 1991)")
        p.add_argument("--k0-reference-t-k", type=float, default=None, metavar="K",
                       help="the temperature at which k0 is given (default 298.15 K)")
    if mesh:
        p.add_argument("--mesh-length-nm", type=float, default=None, metavar="XI",
                       help="the gel's dry mesh (interfacial) length xi_dry in nm: the "
                            "truth's ell = xi_dry / a_d, its range xi/2-2xi (default 4, "
                            "docs/interfacial.md sec. 1)")
    p.add_argument("--paper-constants", action="store_true",
                   help="the paper's constants (eta 1e-3 Pa s, Omega_p 3e-25 m^3, k0 8e-20 "
                        "m^2: D ~ 1e-8 cm^2/s) instead of Omega_p = Omega Omega_f; the "
                        "options given still override them")


def constants_values(args: argparse.Namespace) -> dict[str, Any]:
    """The options given, as the HTTP body's ``constants`` (field names of ConstantsIn)."""
    out: dict[str, Any] = {f: getattr(args, a) for a, f in FIELDS.items()
                           if getattr(args, a, None) is not None}
    if getattr(args, "paper_constants", False):
        out["paper"] = True
    return out


def constants_from_args(args: argparse.Namespace) -> Any:
    """The :class:`PhysicalConstants` of the options given (the rest its defaults)."""
    from dosing.units import PhysicalConstants

    return PhysicalConstants.from_dict(constants_values(args))
