"""Files: the guarded reader of user text, path CSVs, JSON records and output sets."""
