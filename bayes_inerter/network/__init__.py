"""Two-port network description: blocks, cascade, frequency response, compilation."""

from .blocks import Backlash, Block, Deformation, Friction, Inerter, Mass
from .compile import CompiledNetwork, compile_network
from .twoport import Network, abcd, accel_response, cascade

__all__ = [
    "Backlash",
    "Block",
    "Deformation",
    "Friction",
    "Inerter",
    "Mass",
    "Network",
    "CompiledNetwork",
    "abcd",
    "accel_response",
    "cascade",
    "compile_network",
]
