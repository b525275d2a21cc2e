"""Files in and out: BCD cubes and headers, tables, atomic writes."""
