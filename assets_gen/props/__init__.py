"""Prop generators (seashell, sunglasses, umbrella, palm): closed PLY solids with normals and
UVs, in metres, +y up."""
