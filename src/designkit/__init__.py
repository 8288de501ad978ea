"""designkit: symbolic design and verification of robot manipulator controllers."""
__version__ = "0.1.0"
