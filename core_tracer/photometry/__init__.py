"""Physical light for the photometric mode: spectra, bands, CIE colorimetry, sources, materials,
surroundings and outputs (numpy only; the CIE tables ship as data under ``data/``).

The modules, by what a lamp designer does with them:

- ``bands``: ``Bands`` (K wavelength bands over 380–780 nm) and exact band means of a curve.
- ``cie``: ``KM`` (683.002 lm/W), ``xyz_matrix(bands)`` (band radiance → XYZ, Y in cd/m²), ``xy``,
  ``XYZ_TO_LINEAR_REC709``, ``luminous_efficacy``.
- ``spectrum``: ``Spectrum``, a tabulated curve.
- ``sources``: ``incandescent``, ``amber_coated``, ``led``, ``white_led``, ``from_csv``,
  ``BULB_TYPES``, ``bulb_spectral_radiance`` (a Lambertian sphere bulb of flux Φ).
- ``materials``: ``refractive_index`` (n_d and Abbe number), ``MATERIALS``, ``cut_on_filter`` and
  ``FILTERS``, ``absorption_per_mm``, ``mirror_reflectance``, ``rgb_to_reflectance`` (Smits 1999)
  and ``rgb_to_illuminant``.
- ``daylight``: sun in lux, sky and environment images in cd/m², ``STREET_LIGHTING_LUX``.
- ``regulation``: UN R48's red, amber and white regions in xy.
- ``output``: band image → XYZ, luminance, xy; EXR with named channels and units; EV100 exposure;
  a false-colour luminance map with a cd/m² legend.

See README.md beside this file for the units, the sources of every number and the API's promises.
"""
