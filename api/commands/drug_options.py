"""Drug options shared by ``thermogel release``, ``dose`` and ``schedule``."""

from __future__ import annotations

import argparse
from typing import Any

DRUG_FIELDS = ("diffusivity_cm2_s", "solute_radius_nm", "hindrance", "mesh_size_nm",
               "fiber_radius_nm", "free_volume_y", "partition", "release_volume_ul", "load_ug",
               "loading_concentration_ug_per_ul", "reference_temperature_k", "partition_law",
               "mesh_stretch")


def add_drug_options(p: argparse.ArgumentParser, required: bool = False) -> None:
    """The drug in the pore fluid (dosing.payload.drug.DrugModel); any of them switches the dose and
    schedule commands to drug doses."""
    g = p.add_argument_group("drug (a passive solute in the pore fluid)")
    g.add_argument("--drug-diffusivity-cm2-s", dest="diffusivity_cm2_s", type=float,
                   default=0.0 if required else None, metavar="D0",
                   help="the drug's diffusivity in water, cm^2/s (0: carried by the fluid only)"
                        + (" (default 0)" if required else ""))
    g.add_argument("--solute-radius-nm", type=float, default=None,
                   help="Stokes-Einstein radius in nm (gives D0 when it is not given)")
    g.add_argument("--hindrance", choices=["free-volume", "ogston", "amsden", "none"],
                   default=None,
                   help="hindrance law D = D0 f: free-volume (Lustig & Peppas, default), "
                        "ogston (Ogston, Preston & Wells 1973), amsden (1998), none (no "
                        "hindrance, no sieving)")
    g.add_argument("--mesh-size-nm", type=float, default=None,
                   help="mesh size of the swollen gel at T_start in nm (default: the gel's "
                        "dry mesh --mesh-length-nm, the interfacial length's, affine in the "
                        "stretch)")
    g.add_argument("--reference-temperature-k", type=float, default=None,
                   help="temperature at which D0 is given, K (default 298.15; carried to "
                        "T_end by Stokes-Einstein with water's viscosity)")
    g.add_argument("--partition-law", choices=["constant", "ogston"], default=None,
                   help="steric partition K_s(phi) (default: Ogston's with a fibre radius)")
    g.add_argument("--mesh-stretch", choices=["smallest", "volume"], default=None,
                   help="which stretch sets the local mesh (default: the smallest principal)")
    g.add_argument("--no-sieving", dest="sieving", action="store_false", default=None,
                   help="no convective sieving of the expelled fluid's solute")
    g.add_argument("--fiber-radius-nm", type=float, default=None, help="Ogston fibre radius")
    g.add_argument("--free-volume-y", type=float, default=None,
                   help="Y of the free-volume law (default 1)")
    g.add_argument("--partition", type=float, default=None,
                   help="partition K = c_pore / c_medium (default 1)")
    g.add_argument("--release-volume-ul", type=float, default=None,
                   help="a well-mixed release medium in uL (default: a perfect sink)")
    g.add_argument("--load-ug", type=float, default=None, help="drug loaded per bead, ug")
    g.add_argument("--loading-concentration-ug-per-ul", type=float, default=None,
                   help="drug concentration of the loading solution, ug/uL")


def drug_from_args(args: argparse.Namespace, always: bool = False) -> Any:
    """The DrugModel the options describe, or None when none was given (and not ``always``)."""
    given = {f: getattr(args, f, None) for f in (*DRUG_FIELDS, "sieving")}
    given = {k: v for k, v in given.items() if v is not None}
    if not given and not always:
        return None  # a fluid answer: the drug's model (numba, scipy) is not imported
    from dosing.payload.drug import DrugModel

    return DrugModel(**given)
