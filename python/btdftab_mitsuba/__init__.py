# SPDX-License-Identifier: MIT
"""btdftab for Mitsuba 3: the BSDF plugin `btdftab` (docs/mitsuba3.md), over the Python
package btdftab (python/btdftab), which binds libbtdf.

    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    import btdftab_mitsuba          # registers `btdftab` for the variant set
    btdftab_mitsuba.register()      # again after switching variants
"""
import mitsuba as _mi
from btdftab import BtdfError

from .plugin import register

__all__ = ["register", "BtdfError"]

if _mi.variant() is not None:
    register()
