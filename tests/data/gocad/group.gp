GOCAD HeterogeneousGroup 1 
HEADER {
name: two members
}
BEGIN_MEMBERS
GOCAD TSurf 1 
HEADER {
name: member surface
}
TFACE
VRTX 1 0 0 0 
VRTX 2 1 0 0 
VRTX 3 0 1 0 
TRGL 1 2 3 
END
GOCAD VSet 1 
HEADER {
name: member points
}
VRTX 1 5 5 5 
VRTX 2 6 6 6 
END
END_MEMBERS
END
