"""A plugin that subclasses a built-in method and leaves its name to the entry point.

Registered through ``eclipsebench.methods: demo = ebdemo:Demo``
(``ebdemo-0.1.dist-info/entry_points.txt`` beside it). ``Demo`` inherits
BLISS's ``name`` ("bliss"); the entry point names it ``demo``.
"""

from eclipsebench.decorrelate.bliss import Bliss


class Demo(Bliss):
    """BLISS under another name: a plugin's method built on a built-in one."""
