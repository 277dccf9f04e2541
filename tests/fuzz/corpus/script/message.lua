local s = string.rep("\27[31m", 100000) error(s)
