"""Reports: tables and figures read from stored results; reports never integrate."""
