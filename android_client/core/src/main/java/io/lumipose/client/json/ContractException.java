package io.lumipose.client.json;

/** JSON that breaks the contract; {@link #field} names the offending field (dotted path). */
public final class ContractException extends IllegalArgumentException {
    private static final long serialVersionUID = 1L;
    public final String field;

    public ContractException(String field, String message) {
        super(field + ": " + message);
        this.field = field;
    }
}
