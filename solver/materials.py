"""Materials: Young's modulus, density, Poisson's ratio and an allowable strain, SI units.

``Material(E, density, nu, allowable_strain)`` holds any values; the presets below take
theirs from the documents cited (typical values, not specifications: measure the sheet you
build from when it matters). A material goes wherever a density is asked for
(`Structure.add_gravity(material)`), and ``material.E`` / ``material.nu`` into ``add_rod``.

The allowable strain of a preset is the datasheet's elastic limit, its yield stress over its
tensile modulus (sigma_y / E): a surface strain (bending kappa t / 2 plus axial) above it
means the sheet yields somewhere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Material", "PETG", "PLA", "PAPER_PETG", "MATERIALS", "material"]


@dataclass(frozen=True)
class Material:
    """E (Pa), density (kg/m^3), nu (Poisson's ratio) and allowable_strain (dimensionless,
    e.g. 0.027 for 2.7 %); ``name`` and ``source`` say what it is and where the values come
    from. Validated on construction (ValueError naming the field)."""

    E: float
    density: float
    nu: float = 0.38
    allowable_strain: float = float("inf")
    name: str = "custom"
    source: str = ""

    def __post_init__(self):
        for field, low in (("E", 0.0), ("density", 0.0), ("allowable_strain", 0.0)):
            value = getattr(self, field)
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)):
                raise ValueError(f"Material.{field} must be a number; got {value!r}")
            value = float(value)
            finite = np.isfinite(value) or (field == "allowable_strain" and value == np.inf)
            if not (finite and value > low):
                raise ValueError(f"Material.{field} must be finite and > 0; got {value!r}")
            object.__setattr__(self, field, value)
        nu = self.nu
        if isinstance(nu, (bool, np.bool_)) or not isinstance(nu, (int, float, np.number)) \
                or not -1.0 < float(nu) <= 0.5:
            raise ValueError(f"Material.nu (Poisson's ratio) must be in (-1, 0.5]; got {nu!r}")
        object.__setattr__(self, "nu", float(nu))

    @property
    def G(self) -> float:
        """Shear modulus E / (2 (1 + nu)), Pa."""
        return self.E / (2.0 * (1.0 + self.nu))


#: PETG sheet, Eastman Chemical Company, "Eastman Spectar(TM) Clear Copolyester, Technical
#: Data Sheet" (web TDS, undated; consulted 2026), sheet 3 mm thick: density 1.23 g/cm^3
#: (ASTM D1505), tensile modulus 1.80 GPa and tensile stress at yield 48 MPa (ASTM D638),
#: elongation at yield 5.0 %. The sheet gives no Poisson's ratio: 0.38, the paper's.
#: Allowable strain: 48 MPa / 1.80 GPa = 2.67 %.
PETG = Material(E=1.80e9, density=1.23e3, nu=0.38, allowable_strain=48e6 / 1.80e9,
                name="PETG",
                source="Eastman Spectar Clear copolyester (PETG sheet) TDS, Eastman Chemical "
                       "Company (undated web TDS, consulted 2026)")

#: PLA, NatureWorks LLC, "Ingeo(TM) Biopolymer 4043D Technical Data Sheet, 3D Printing
#: Monofilament - General Purpose Grade" (undated TDS, consulted 2026), injection-moulded
#: amorphous bars: specific gravity 1.24 (ASTM D792), tensile modulus 3.6 GPa and tensile
#: yield strength 60 MPa (ASTM D882), tensile elongation 6 %. The sheet gives no Poisson's
#: ratio: 0.36 (a typical value for PLA, an assumption). Allowable strain: 60 MPa / 3.6 GPa
#: = 1.67 %.
PLA = Material(E=3.6e9, density=1.24e3, nu=0.36, allowable_strain=60e6 / 3.6e9, name="PLA",
               source="NatureWorks Ingeo 4043D TDS (3D printing monofilament), NatureWorks "
                      "LLC (undated TDS, consulted 2026)")

#: The paper's PETG (Rahman et al. 2024, Sec. 2: E = 2.2 GPa from the first resonance of a
#: cantilevered strip, rho = 1.3e3 kg/m^3, nu = 0.38). The paper gives no strength: the
#: allowable strain is the PETG datasheet's elastic limit (`PETG`).
PAPER_PETG = Material(E=2.2e9, density=1.3e3, nu=0.38,
                      allowable_strain=PETG.allowable_strain, name="paper",
                      source="Rahman et al. (2024), Int. J. Solids Struct. 300, 112917, "
                             "Sec. 2; allowable strain from the PETG datasheet")

#: the presets by name (lower case), for command lines and configuration files
MATERIALS = {"petg": PETG, "pla": PLA, "paper": PAPER_PETG}


def material(value) -> Material:
    """A `Material` from itself or a preset's name ("petg", "pla", "paper"; any case)."""
    if isinstance(value, Material):
        return value
    if isinstance(value, str) and value.lower() in MATERIALS:
        return MATERIALS[value.lower()]
    raise ValueError(f"material must be a Material or one of {sorted(MATERIALS)}; got {value!r}")
