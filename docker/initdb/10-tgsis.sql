-- First start of the container: PostGIS and tgsis in the POSTGRES_DB database.
CREATE EXTENSION IF NOT EXISTS postgis;
CREATE EXTENSION IF NOT EXISTS tgsis;
