GOCAD SGrid 1 
HEADER {
name: porosity grid
ascii: off
}
GOCAD_ORIGINAL_COORDINATE_SYSTEM
NAME Default
AXIS_NAME X Y Z
AXIS_UNIT m m m
ZPOSITIVE Elevation
END_ORIGINAL_COORDINATE_SYSTEM
AXIS_N 11 11 3 
PROP_ALIGNMENT CELLS
POINTS_FILE porosity_grid__points@@
PROPERTY 1 porosity
PROPERTY_CLASS_HEADER 1 porosity {
kind: Real Number
}
PROP_FILE 1 porosity_grid__porosity@@
END
GOCAD TSurf 1 
HEADER {
name: horizon
}
TFACE
VRTX 1 0 0 0 
VRTX 2 10 0 0 
VRTX 3 0 10 1 
TRGL 1 2 3 
END
GOCAD Model3d 1 
HEADER {
name: structural model
}
SURFACE horizon
TFACE
KEYVERTICES 1 2 3
END
GOCAD PLine 1 
HEADER {
name: trace
}
ILINE
VRTX 1 0 0 0 
VRTX 2 10 0 0 
SEG 1 2 
END
