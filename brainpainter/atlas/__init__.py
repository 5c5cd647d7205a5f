"""The atlas model: atlases, templates (meshes), label sets, user atlases and their configs,
volumes, and the plugin registry.
"""
