"""What every generator shares: the contract (parameter dataclass, :class:`Generator`, the CLI made
from it) and the helpers that keep outputs reproducible (staging, manifests, PLY/map writers,
meshing, the camera)."""
from assets_gen.core.generator import Generator, Job
from assets_gen.core.params import GeneratorError, Params, param, reading, require

__all__ = ["Generator", "GeneratorError", "Job", "Params", "param", "reading", "require"]
