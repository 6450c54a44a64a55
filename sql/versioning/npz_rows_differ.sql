-- tgsis.npz_rows_differ(mesh, rows...): what of a solution's rows is not in its .npz (NULL when they hold the same mesh).
-- tgsis.resolve_region keeps an average or manual solution twice: the .npz
-- the Python merge applies and the rows the psql merge applies. The Python
-- client records both from one mesh; a psql user may give the .npz of one
-- mesh and the rows of another, and the two merges would then write two
-- results of one solution. This reads the .npz as numpy.savez writes it
-- (a zip of stored, uncompressed members, ZIP64 sizes; each an .npy:
-- magic, header, the array's bytes; tgsis.db.regions.state_to_npz) and
-- compares it with the rows: the ids, coordinates and cells byte for byte,
-- the property columns by name, their values per element as the Python
-- client converts them to float8 (any NaN equal to NaN). The bytes of each
-- member are turned big-endian in one pass (its hex reversed, then each
-- byte's two digits swapped back: the elements in reverse order), so that
-- they compare with float8send/int8send. A member of a type SQL does not
-- read (neither integer, boolean nor float4/float8) is not compared (the
-- Python merge compares the two copies too: tgsis.db.regions).
CREATE FUNCTION tgsis.npz_rows_differ(p_mesh bytea, p_vertex_ids bigint[], p_vertices float8[], p_cell_ids bigint[],
                                      p_cells bigint[], p_vertex_columns text[], p_vertex_values float8[],
                                      p_cell_columns text[], p_cell_values float8[])
RETURNS text
LANGUAGE plpgsql
IMMUTABLE
PARALLEL SAFE
SET search_path = pg_catalog, pg_temp
AS $$
DECLARE
    v_at     integer := 0;
    v_len    integer := octet_length(p_mesh);
    v_nlen   integer;
    v_elen   integer;
    v_size   bigint;  -- (a bytea holds less than 1 GB: integer offsets below)
    v_name   text;
    v_extra  bytea;
    v_data   bytea;
    v_hlen   integer;
    v_head   text;
    v_names  text[] := '{}';
    v_descr  text[] := '{}';
    v_be     bytea[] := '{}';
    v_i      integer;
    v_e      integer;
    v_word   text;
    v_cols   text[];
    v_vals   float8[];
    v_n      integer;
    v_col    integer;
    v_width  integer;
    v_bad    bigint;
BEGIN
    -- the members, in the order of their local headers (a later one of a name wins, as zipfile reads it)
    WHILE v_at + 30 <= v_len AND substr(p_mesh, v_at + 1, 4) = '\x504b0304'::bytea LOOP
        IF get_byte(p_mesh, v_at + 8) <> 0 OR get_byte(p_mesh, v_at + 9) <> 0 THEN
            RETURN 'a member is compressed';
        END IF;
        v_size := get_byte(p_mesh, v_at + 18) + 256::bigint * get_byte(p_mesh, v_at + 19)
                  + 65536::bigint * get_byte(p_mesh, v_at + 20) + 16777216::bigint * get_byte(p_mesh, v_at + 21);
        v_nlen := get_byte(p_mesh, v_at + 26) + 256 * get_byte(p_mesh, v_at + 27);
        v_elen := get_byte(p_mesh, v_at + 28) + 256 * get_byte(p_mesh, v_at + 29);
        v_name := convert_from(substr(p_mesh, v_at + 31, v_nlen), 'UTF8');
        IF v_size = 4294967295 THEN  -- ZIP64: the sizes in the extra field 0x0001 (uncompressed, compressed)
            v_extra := substr(p_mesh, v_at + 31 + v_nlen, v_elen);
            v_e := 0;
            v_size := NULL;
            WHILE v_e + 4 <= octet_length(v_extra) LOOP
                IF get_byte(v_extra, v_e) = 1 AND get_byte(v_extra, v_e + 1) = 0 THEN
                    v_size := ('x' || (SELECT string_agg(substr(encode(substr(v_extra, v_e + 13, 8), 'hex'), 2 * k + 1, 2), ''
                                                         ORDER BY k DESC) FROM generate_series(0, 7) AS k))::bit(64)::bigint;
                END IF;
                v_e := v_e + 4 + get_byte(v_extra, v_e + 2) + 256 * get_byte(v_extra, v_e + 3);
            END LOOP;
            IF v_size IS NULL THEN
                RETURN format('member %s has no ZIP64 sizes', v_name);
            END IF;
        END IF;
        IF v_size > v_len THEN
            RETURN format('member %s is longer than the .npz', v_name);
        END IF;
        v_data := substr(p_mesh, v_at + 31 + v_nlen + v_elen, v_size::integer);
        v_at := v_at + 30 + v_nlen + v_elen + v_size::integer;
        IF substr(v_data, 1, 6) <> '\x934e554d5059'::bytea THEN
            RETURN format('member %s is no .npy', v_name);
        END IF;
        IF get_byte(v_data, 6) = 1 THEN
            v_hlen := get_byte(v_data, 8) + 256 * get_byte(v_data, 9);
            v_head := convert_from(substr(v_data, 11, v_hlen), 'LATIN1');
            v_data := substr(v_data, 11 + v_hlen);
        ELSE
            v_hlen := get_byte(v_data, 8) + 256 * get_byte(v_data, 9) + 65536 * get_byte(v_data, 10);
            v_head := convert_from(substr(v_data, 13, v_hlen), 'LATIN1');
            v_data := substr(v_data, 13 + v_hlen);
        END IF;
        IF v_head ~ '''fortran_order'':\s*True' THEN
            RETURN format('member %s is in Fortran order', v_name);
        END IF;
        v_names := v_names || regexp_replace(v_name, '\.npy$', '');
        v_descr := v_descr || substring(v_head FROM '''descr'':\s*''([^'']*)''');
        -- big-endian elements in reverse order (one byte elements: the bytes reversed)
        v_be := v_be || decode(regexp_replace(reverse(encode(v_data, 'hex')), '(.)(.)', '\2\1', 'g'), 'hex');
    END LOOP;

    -- the geometry, byte for byte: ids and cells int64, coordinates float64, C order
    FOR v_i IN 1 .. 4 LOOP
        v_word := (ARRAY['vertex_ids', 'vertices', 'cell_ids', 'cells'])[v_i];
        v_e := array_position(v_names, v_word);
        IF v_e IS NULL THEN
            RETURN format('the .npz has no %s', v_word);
        END IF;
        IF v_descr[v_e] <> (CASE v_word WHEN 'vertices' THEN '<f8' ELSE '<i8' END)
           OR v_be[v_e] <> (CASE WHEN v_word = 'vertices'
                                THEN coalesce((SELECT string_agg(float8send(x), '' ORDER BY o DESC)
                                                 FROM unnest(p_vertices) WITH ORDINALITY AS u(x, o)), ''::bytea)
                                ELSE coalesce((SELECT string_agg(int8send(x), '' ORDER BY o DESC)
                                                 FROM unnest(CASE v_word WHEN 'vertex_ids' THEN p_vertex_ids
                                                                         WHEN 'cell_ids' THEN p_cell_ids ELSE p_cells END)
                                                      WITH ORDINALITY AS u(x, o)), ''::bytea) END) THEN
            RETURN format('its %s are not the rows''', v_word);
        END IF;
    END LOOP;

    -- the properties: the same names, each value as the Python client gives it (float8; NaN for none)
    FOR v_i IN 1 .. 2 LOOP
        v_word := (ARRAY['vertex', 'cell'])[v_i];
        v_cols := CASE v_i WHEN 1 THEN p_vertex_columns ELSE p_cell_columns END;
        v_vals := CASE v_i WHEN 1 THEN p_vertex_values ELSE p_cell_values END;
        v_n := CASE v_i WHEN 1 THEN cardinality(p_vertex_ids) ELSE cardinality(p_cell_ids) END;
        IF ARRAY(SELECT c FROM unnest(v_cols) AS c ORDER BY c)
           IS DISTINCT FROM ARRAY(SELECT substr(m, length(v_word) + 2) FROM unnest(v_names) AS m
                                   WHERE m LIKE v_word || ':%' GROUP BY m ORDER BY 1) THEN
            RETURN format('its %s property columns are not the rows''', v_word);
        END IF;
        FOR v_col IN 1 .. coalesce(cardinality(v_cols), 0) LOOP
            v_e := (SELECT max(o) FROM unnest(v_names) WITH ORDINALITY AS m(m, o) WHERE m = v_word || ':' || v_cols[v_col]);
            v_width := CASE WHEN v_descr[v_e] ~ '^[<|](f8|i8|u8)$' THEN 8 WHEN v_descr[v_e] ~ '^[<|](f4|i4|u4)$' THEN 4
                            WHEN v_descr[v_e] ~ '^[<|](i2|u2)$' THEN 2 WHEN v_descr[v_e] ~ '^\|(i1|u1|b1)$' THEN 1 END;
            CONTINUE WHEN v_width IS NULL;  -- (a type SQL does not read: the Python merge compares it)
            IF octet_length(v_be[v_e]) <> v_width * v_n THEN
                RETURN format('its %s property %s has %s bytes for %s rows', v_word, v_cols[v_col],
                              octet_length(v_be[v_e]), v_n);
            END IF;
            SELECT count(*) INTO v_bad
              FROM generate_series(1, v_n) AS g(i),
                   LATERAL (SELECT v_vals[(g.i - 1) * cardinality(v_cols) + v_col] AS x,
                                   substr(v_be[v_e], (v_n - g.i) * v_width + 1, v_width) AS b) AS e
             WHERE NOT CASE
                 WHEN v_descr[v_e] ~ 'f8$' THEN e.b = float8send(e.x)
                      OR (e.x = 'NaN' AND (get_byte(e.b, 0) & 127) = 127 AND (get_byte(e.b, 1) & 240) = 240
                          AND e.b NOT IN ('\x7ff0000000000000'::bytea, '\xfff0000000000000'::bytea))
                 WHEN v_descr[v_e] ~ 'f4$' THEN CASE  -- (a float8 no float4 holds is none of the .npz's: no cast)
                          WHEN e.x = 'NaN' OR (abs(e.x) > 3.4028234663852886e38 AND abs(e.x) <> 'Infinity')
                               OR (e.x <> 0 AND abs(e.x) < 1.401298464324817e-45) THEN false
                          ELSE e.x = e.x::real::float8 AND e.b = float4send(e.x::real) END
                      OR (e.x = 'NaN' AND (get_byte(e.b, 0) & 127) = 127 AND (get_byte(e.b, 1) & 128) = 128
                          AND e.b NOT IN ('\x7f800000'::bytea, '\xff800000'::bytea))
                 ELSE e.x = trunc(e.x) AND abs(e.x) < 9.2e18
                      AND e.x = (('x' || encode(e.b, 'hex'))::bit(64) >> (64 - 8 * v_width))::bigint
                                - CASE WHEN v_descr[v_e] ~ 'i[124]$' AND get_byte(e.b, 0) >= 128
                                       THEN 2::numeric ^ (8 * v_width) ELSE 0 END
                 END IS TRUE;
            IF v_bad > 0 THEN
                RETURN format('its %s property %s holds other values than the rows (%s)', v_word, v_cols[v_col], v_bad);
            END IF;
        END LOOP;
    END LOOP;
    RETURN NULL;
END
$$;

COMMENT ON FUNCTION tgsis.npz_rows_differ(bytea, bigint[], float8[], bigint[], bigint[], text[], float8[], text[], float8[]) IS
    'for tgsis.resolve_region: what of an average/manual solution''s rows (for the psql merge) is not in its .npz (for the Python merge), NULL when both hold one mesh; reads the .npz numpy.savez writes';

-- internal to tgsis.resolve_region (SECURITY DEFINER): not executable by PUBLIC
REVOKE ALL ON FUNCTION tgsis.npz_rows_differ(bytea, bigint[], float8[], bigint[], bigint[], text[], float8[], text[], float8[]) FROM PUBLIC;
