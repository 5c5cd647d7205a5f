"""Files in and out: safe opening and reading of the user's files, PNG/JSON writing, the output
transaction.
"""
