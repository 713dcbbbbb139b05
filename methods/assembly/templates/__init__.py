"""The templates: plain Python functions copied verbatim into kernel modules, where the names they
leave free are bound (methods/assembly/bindings.py). They import the real constants they read
(templates/slots.py) so that they are valid Python; the module holds the same values in its text."""
