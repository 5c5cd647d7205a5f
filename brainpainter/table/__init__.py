"""The user's table: reading rows x regions, cell values, matching column names to an atlas, the
check report.
"""
