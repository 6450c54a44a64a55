-- tgsis.partition_model_storage(model bigint, partitions bigint): the same, for numbers written without casts.
-- The function takes smallint and integer; psql's 'partition_model_storage(1, 8)'
-- matched no function (42883), and a number beyond those types came back as
-- a raw 22003 or 42883 naming nothing. This overload takes any integer,
-- refuses one out of range by name (TG100) and calls the function.
CREATE FUNCTION tgsis.partition_model_storage(p_model bigint, p_partitions bigint)
RETURNS text[]
LANGUAGE plpgsql
VOLATILE
SET search_path = pg_catalog, pg_temp
AS $$
BEGIN
    IF p_model IS NULL OR p_model NOT BETWEEN 0 AND 32767 THEN
        RAISE EXCEPTION 'data model % does not exist', coalesce(p_model::text, 'NULL')
            USING ERRCODE = 'TG200', HINT = 'in psql: SELECT model, name FROM tgsis.data_models lists the data models';
    END IF;
    IF p_partitions IS NULL OR p_partitions NOT BETWEEN 2 AND 1024 THEN
        RAISE EXCEPTION 'number of partitions % is out of range', coalesce(p_partitions::text, 'NULL')
            USING ERRCODE = 'TG100', HINT = 'give 2 to 1024 partitions';
    END IF;
    RETURN tgsis.partition_model_storage(p_model::smallint, p_partitions::integer);
END
$$;

REVOKE ALL ON FUNCTION tgsis.partition_model_storage(bigint, bigint) FROM PUBLIC;

COMMENT ON FUNCTION tgsis.partition_model_storage(bigint, bigint) IS
    'tgsis.partition_model_storage(smallint, integer) for integers of any width (partition_model_storage(1, 8) in psql): a model or number of partitions out of range is refused by name (TG200, TG100)';
