GOCAD Model3d 1 
HEADER {
name: small model
}
GOCAD_ORIGINAL_COORDINATE_SYSTEM
NAME Default
AXIS_NAME X Y Z
AXIS_UNIT m m m
ZPOSITIVE Elevation
END_ORIGINAL_COORDINATE_SYSTEM
TSURF horizon
TSURF box side
TFACE 1  top horizon
  0 0 -50 
  10 0 -50 
  0 10 -50 
TFACE 2  boundary box side
  0 0 0 
  10 0 0 
  0 0 -100 
TFACE 3  boundary box side
  0 10 0 
  10 10 0 
  0 10 -100 
REGION 4  Universe 
  -2  -3  0
REGION 5  Upper 
  +1  +2  +3  0
REGION 6  Lower 
  -1  +2  +3 
  0
SURFACE box
  2  3  0
LAYER Cover
  5  0
END
GOCAD TSurf 1 
HEADER {
name_in_model_list: horizon
name: horizon
}
GEOLOGICAL_FEATURE horizon
GEOLOGICAL_TYPE top
PROPERTY_CLASS_HEADER X {
kind: X
unit: m
}
PROPERTY_CLASS_HEADER Z {
kind: Depth
unit: m
is_z: on
}
TFACE
VRTX 1 0 0 -50 
VRTX 2 10 0 -50 
VRTX 3 0 10 -50 
VRTX 4 10 10 -50 
TRGL 1 2 3 
TRGL 2 4 3 
BSTONE 1 
BORDER 5 1 2 
END
GOCAD TSurf 1 
HEADER {
name_in_model_list: box side
name: box side
}
GEOLOGICAL_TYPE boundary
TFACE
VRTX 1 0 0 0 
VRTX 2 10 0 0 
VRTX 3 0 0 -100 
TRGL 1 2 3 
TFACE
VRTX 4 0 10 0 
VRTX 5 10 10 0 
VRTX 6 0 10 -100 
TRGL 4 5 6 
END
