"""Offline tools that build brainpainter's bundled data from FreeSurfer files."""
