"""Photometry stage: BCD cubes to per-frame tables (paper Section 3.1, Appendix B).

- :mod:`.pipeline` - folders of BCD files to one table per epoch
  (:func:`~.pipeline.photometry_tables`);
- :mod:`.measure` - the measurement set on a stack of frames
  (:func:`~.measure.measure_stack`, arrays in, arrays out);
- :mod:`.kernels`, :mod:`.overlap` - the numba kernels (centroids, noise
  pixels, exact aperture overlaps, annulus, stamps);
- :mod:`.clean` - flag bits, running medians, cosmic rays, outliers;
- :mod:`.table` - :func:`~.table.write_photometry`, :func:`~.table.read_photometry`;
- :mod:`.binning` - :func:`~.binning.bin_table`.
"""
