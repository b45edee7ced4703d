"""empact: dynamic analysis and simulation of electromechanically actuated pushbelt CVTs."""
__version__ = "0.1.0"
