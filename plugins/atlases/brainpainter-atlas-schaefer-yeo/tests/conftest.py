# brainpainter's test helpers as a pytest plugin: the brainpainter_home and stand_in_renderer fixtures.
pytest_plugins = ["brainpainter.testing"]
