"""gnibench: benchmark and verification suite for integrators of ODEs with first integrals."""
__version__ = "0.1.0"
