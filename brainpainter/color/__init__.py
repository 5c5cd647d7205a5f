"""Colours: parsing and formatting colour values, and the colour scale that maps numbers to
colours.
"""
