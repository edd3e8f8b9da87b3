"""Every numeric tolerance and tuning constant of splatedit, in one place.

Units: lengths are in model units unless the name says ``_PX`` (pixels) or
``_REL`` (relative to the model's bounding-box diagonal).

The constants live in one package, a module per layer (``model``, ``io``,
``deform``, ``select``, ``render``, ``app``); each is re-exported here, so
code imports ``from splatedit.tolerances import NAME`` and a test patches
``splatedit.tolerances.NAME`` where the code reads it through this module.
A new constant goes into its layer's module, at the end of a section titled
with its topic, with the measurement behind it in its comment.
"""

from splatedit.tolerances.model import *  # noqa: F401,F403
from splatedit.tolerances.io import *  # noqa: F401,F403
from splatedit.tolerances.deform import *  # noqa: F401,F403
from splatedit.tolerances.select import *  # noqa: F401,F403
from splatedit.tolerances.render import *  # noqa: F401,F403
from splatedit.tolerances.app import *  # noqa: F401,F403
