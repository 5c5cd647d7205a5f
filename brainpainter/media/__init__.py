"""What a researcher takes away: figures, movies, colour bars, reference images, interactive
export, notebook plots.
"""
