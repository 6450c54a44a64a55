-- tgsis.chunk_decode_sql(table, alias): the SQL pieces that decode the chunk versions of a chunk table into rows.
-- The decoded view (tgsis.create_chunk_view) and the relational face
-- (tgsis.create_chunk_face) read chunks the same way: the arrays unnested
-- side by side WITH ORDINALITY (o), the local id = (chunk << shift) + (o - 1)
-- (the slot first: id 2^63 - 1 is slot 1024 of the last chunk, and
-- chunk << shift + o would overflow before the subtraction), vertex ids from
-- vbase and the differences or from the _wide columns, and a slot present
-- when its first column is not NULL (NULL marks a hole). One function builds
-- the pieces, so that a fix of the decoding reaches every reader (a copy of
-- this loop in the face kept the overflow the hostile review fixed in the
-- view). p_alias is the chunk table's alias in the caller's FROM; the
-- ordinality and the unnested columns are read as u.<name> and u.o. A
-- class's property table (columns of role 'value', tgsis.chunk_columns) may
-- hold NULL values: there a slot is present when holes does not list it.
-- Such a column's whole array NULL is seen only by a snapshot older than an
-- added property's fill (tgsis.alter_chunk_table adds it without a rewrite,
-- then UPDATEs it): reading that column gives 40001
-- (tgsis.chunk_array_missing), not NULL where new snapshots read the default.
-- A vector property (role 'vector', size k: a 2-D array, slots x k) is
-- unnested as k one-dimensional columns, its component slices arr[:][i:i]
-- (aliases <name>#i: no property name holds '#'), read back as ARRAY[...] of
-- them, NULL where its first component is (a NULL vector or a hole: the row
-- table refuses a NULL element, and tgsis.chunk_encoding_checks a row partly
-- NULL). Each slice detoasts the array once per chunk: k reads of it.
-- A point (role 'point': a 2-D double precision[], slots x m, m per chunk)
-- needs a fifth piece, joins: a LATERAL subquery per chunk flattening the
-- array once (ARRAY(SELECT coalesce(x, 0) FROM unnest(arr) AS x), OFFSET 0:
-- a hole's NULLs made 0, never read, so that no slice carries a NULL bitmap
-- a row's array has not: array_send equal to the row table's) with m =
-- array_length(arr, 2), which every reader places between the chunk table
-- and the unnest ('' for tables without points); the unnest takes the
-- first coordinates arr[:][1:1] (NULL at a hole: the row table refuses a
-- NULL coordinate) and the slot's point is the slice
-- flat[(o - 1) * m + 1 : o * m], a one-dimensional array from 1 as the row
-- table holds it (docs/storage.md, "The points in chunks": a per-row slice of
-- the 2-D array costs 50x, the flatten per chunk 4.35x the row table's scan).
CREATE FUNCTION tgsis.chunk_decode_sql(p_table text, p_alias text)
RETURNS TABLE (select_list text, arrays text, aliases text, present text, joins text)
LANGUAGE plpgsql
STABLE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_shift  integer;
    v_refs   text[];
    v_first  text;
    v_select text[] := '{}';
    v_arrays text[] := '{}';
    v_alias  text[] := '{}';
    v_lat    text := '';
    v_a      text := quote_ident(p_alias);
    v_c      record;
BEGIN
    v_shift := (SELECT round(log(2, r.chunksize))::integer FROM tgsis.chunk_registry(p_table) r);
    v_refs := ARRAY(SELECT c.name FROM tgsis.chunk_columns(p_table) c WHERE c.role = 'ref' ORDER BY c.colorder);
    FOR v_c IN SELECT c.name, c.role, c.typename, c.size FROM tgsis.chunk_columns(p_table) c ORDER BY c.colorder LOOP
        IF v_c.role = 'key' THEN
            v_select := v_select || format('%s.%I', v_a, v_c.name);
        ELSIF v_c.role = 'chunk' THEN
            v_select := v_select || format('(%s.chunk << %s) + (u.o - 1) AS %I', v_a, v_shift, v_c.name);
        ELSIF v_c.role = 'vector' THEN
            v_arrays := v_arrays || ARRAY(SELECT format('%s.%I[:][%s:%s]', v_a, v_c.name, i, i) FROM generate_series(1, v_c.size) AS i
                                           ORDER BY i);
            v_alias := v_alias || ARRAY(SELECT quote_ident(v_c.name || '#' || i) FROM generate_series(1, v_c.size) AS i ORDER BY i);
            -- (the array itself as the value argument, not a NULL constant: a call of constants only is a STABLE
            -- call the planner may evaluate to estimate an expression, which raised 40001 on chunks of no NULL array)
            v_select := v_select || format('CASE WHEN %1$s.%2$I IS NULL THEN tgsis.chunk_array_missing(%3$L, %4$L, %1$s.%2$I) '
                                           'WHEN u.%6$I IS NULL THEN NULL ELSE ARRAY[%7$s] END AS %2$I',
                                           v_a, v_c.name, p_table, v_c.name, v_c.typename, v_c.name || '#1',
                                           (SELECT string_agg(format('u.%I', v_c.name || '#' || i), ', ' ORDER BY i)
                                              FROM generate_series(1, v_c.size) AS i));
            v_first := coalesce(v_first, format('NOT coalesce(u.o = ANY (%s.holes), false)', v_a));
        ELSIF v_c.role = 'point' THEN
            -- flattened once per chunk (the LATERAL piece, OFFSET 0: not pulled up into a per-row expression), sliced
            -- per slot; the first coordinate's slice drives the ordinality and marks a hole (NULL)
            v_lat := v_lat || format(' CROSS JOIN LATERAL (SELECT ARRAY(SELECT coalesce(x, 0) FROM unnest(%1$s.%2$I) AS x) AS flat, '
                                     'array_length(%1$s.%2$I, 2) AS m OFFSET 0) AS %3$I',
                                     v_a, v_c.name, 'p#' || p_alias || '#' || v_c.name);
            v_arrays := v_arrays || format('%s.%I[:][1:1]', v_a, v_c.name);
            v_alias := v_alias || quote_ident(v_c.name || '#1');
            v_select := v_select || format('CASE WHEN u.%1$I IS NOT NULL THEN %2$I.flat[(u.o - 1) * %2$I.m + 1 : u.o * %2$I.m] END AS %3$I',
                                           v_c.name || '#1', 'p#' || p_alias || '#' || v_c.name, v_c.name);
            v_first := coalesce(v_first, format('u.%I IS NOT NULL', v_c.name || '#1'));
        ELSIF v_c.role IN ('float', 'value') THEN
            v_arrays := v_arrays || format('%s.%I', v_a, v_c.name);
            v_alias := v_alias || quote_ident(v_c.name);
            -- a NULL array: a snapshot older than an added property's fill (tgsis.alter_chunk_table) reads 40001 for it
            v_select := v_select || CASE WHEN v_c.role = 'value'
                                         THEN format('CASE WHEN %s.%I IS NULL THEN tgsis.chunk_array_missing(%L, %L, u.%I) '
                                                     'ELSE u.%I END AS %I', v_a, v_c.name, p_table, v_c.name, v_c.name,
                                                     v_c.name, v_c.name)
                                         ELSE format('u.%I', v_c.name) END;
            v_first := coalesce(v_first, CASE WHEN v_c.role = 'float' THEN format('u.%I IS NOT NULL', v_c.name)
                                              ELSE format('NOT coalesce(u.o = ANY (%s.holes), false)', v_a) END);
        ELSE
            v_arrays := v_arrays || format('%s.%I', v_a, v_c.name) || format('%s.%I', v_a, v_c.name || '_wide');
            v_alias := v_alias || quote_ident(v_c.name) || quote_ident(v_c.name || '_wide');
            -- the first ref relative to vbase, the others to the first
            v_select := v_select || format('CASE WHEN %s.vbase IS NOT NULL THEN %s.vbase + %s ELSE u.%I END AS %I', v_a, v_a,
                                           CASE WHEN v_c.name = v_refs[1] THEN format('u.%I', v_c.name)
                                                ELSE format('u.%I + u.%I', v_refs[1], v_c.name) END,
                                           v_c.name || '_wide', v_c.name);
            v_first := coalesce(v_first, format('(u.%I IS NOT NULL OR u.%I IS NOT NULL)', v_c.name, v_c.name || '_wide'));
        END IF;
    END LOOP;
    RETURN QUERY SELECT array_to_string(v_select, ', '), array_to_string(v_arrays, ', '), array_to_string(v_alias, ', '), v_first,
                        v_lat;
END
$$;

REVOKE ALL ON FUNCTION tgsis.chunk_decode_sql(text, text) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.chunk_decode_sql(text, text) IS
    'the SQL pieces decoding tgsis.<table>_chunk (alias p_alias) into the row table''s columns: the select list (ids from chunk and ordinality u.o, vertex ids from vbase or _wide), the arrays to unnest, their aliases, the test of a present slot, and a LATERAL join to place between the chunk table and the unnest (a point''s array flattened once per chunk; empty without points); read by tgsis.create_chunk_view and create_chunk_face';
