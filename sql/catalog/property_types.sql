-- The column types a feature class may give its properties: no arbitrary SQL
-- can come in through a type name. Vertex and cell properties must be
-- fixed-width numbers (they travel through binary COPY as numpy arrays).
CREATE TABLE tgsis.property_types (
    typename text    PRIMARY KEY,
    aliases  text[]  NOT NULL DEFAULT '{}',
    per_cell boolean NOT NULL
);

COMMENT ON TABLE tgsis.property_types IS 'types allowed for feature-class properties, with accepted spellings';
COMMENT ON COLUMN tgsis.property_types.typename IS 'canonical type name, as format_type() prints it';
COMMENT ON COLUMN tgsis.property_types.aliases IS 'other accepted spellings (lower case)';
COMMENT ON COLUMN tgsis.property_types.per_cell IS 'allowed for vertex/cell properties (fixed-width numbers), not only per feature';

INSERT INTO tgsis.property_types (typename, aliases, per_cell) VALUES
    ('smallint',                 '{int2}',                         true),
    ('integer',                  '{int,int4}',                     true),
    ('bigint',                   '{int8}',                         true),
    ('real',                     '{float4}',                       true),
    ('double precision',         '{float8,float,double}',          true),
    ('boolean',                  '{bool}',                         true),
    ('numeric',                  '{decimal}',                      false),
    ('text',                     '{varchar,string}',               false),
    ('date',                     '{}',                             false),
    ('timestamp with time zone', '{timestamptz}',                  false),
    ('jsonb',                    '{json}',                         false);
