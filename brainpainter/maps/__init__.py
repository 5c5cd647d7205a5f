"""Maps: values per vertex of the cortex, and volumes brought onto it."""
