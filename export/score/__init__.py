"""`cavatar score`: what the board publishes, scored against the virtual carpet's truth.

capture (the real runtime on sim://…&speed=0) → judge (CLEAR MOT on the carpet plane, pose
errors of matched people: :mod:`export.metrics`) → summary (overall, per number of people, per
activity) → JSON, Markdown (:mod:`.markdown`), a PNG timeline (:mod:`.plot`) and the README
block (:mod:`.readme`). Numpy, scipy and onnxruntime only: no torch.
"""
