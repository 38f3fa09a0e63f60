"""FON functions, one module per group of the manual's section 3; see registry.py."""
