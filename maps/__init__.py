"""The design-map database: load a map and look up unit properties by interpolation.

    from snapmorph.maps import DesignMap
    dm = DesignMap.load()                       # maps/data/default.nc (see DesignMap.load)
    dm.at(h_over_L=0.2, t_over_L=0.005, w_over_L=0.05)["theta"]
    dm.at(h_over_L=0.2, t_over_L=0.005, w_over_L=0.05, b_over_L=0.05)["theta"]   # the paper's b = w
"""

if __name__ != "snapmorph.maps":  # imported under its pre-0.2 top-level name `maps`
    from _snapmorph_legacy import alias_old_name  # warns, then hands out snapmorph.maps

    alias_old_name(__name__)

from snapmorph.maps.designmap import (CI_MAP, DEFAULT_B_OVER_L, DEFAULT_MAP, REFERENCE_MAP,
                                      STATE_NAMES, DesignMap, MapDomainError, MapFileError,
                                      OldSchemaWarning)

__all__ = ["DesignMap", "MapDomainError", "MapFileError", "OldSchemaWarning", "STATE_NAMES",
           "DEFAULT_MAP", "CI_MAP", "REFERENCE_MAP", "DEFAULT_B_OVER_L"]
