"""cogniframe: one parameter file in, a buildable CogniFly exoskeleton out.

Stages, data flowing one way: spec -> frame -> partlist -> parts -> export -> analysis -> report.
Importing this package has no side effects and does not import CadQuery.
"""

__version__ = "0.1.0"
