"""CAvatar Edge runtime: carpet sources, frame assembly, scene logic, inference, body model, sinks.

Imports nothing heavier than numpy at package import; torch is never imported here
(a test proves it).
"""

__version__ = "0.1.0"
