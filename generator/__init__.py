"""EasyLab: model-based development of firmware for robots and mechatronic systems."""

__version__ = "0.1.0"
